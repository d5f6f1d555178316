// Grasping tissue (contact/tissue_grasp.h, issue 28), each against a value the grasp code does not
// compute: the mixed LCP's optimality conditions, the 1 kHz solver against the frame's dense one,
// the jaws' points against a search of every node, and a block pulled by its grasped top against
// the linear static solve with the grasped nodes' displacement imposed (Dirichlet), a second
// method for the same equilibrium.
#include "contact/tissue_grasp.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "contact/contact_solver.h"
#include "contact/haptic_contact_rows.h"
#include "contact/haptic_lcp_solver.h"
#include "contact/linear_contact_model.h"
#include "contact/visual_frame.h"
#include "fem/lattice_mesher.h"
#include "fem/stiffness_assembly.h"
#include "fem/tet_mesh.h"
#include "fem/time_stepper.h"

namespace hapsim::contact {
namespace {

// A symmetric positive definite n × n matrix with entries of order 1.
Eigen::MatrixXd MakeSpd(int n, std::mt19937* rng) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd A(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) A(i, j) = normal(*rng);
  return A * A.transpose() / n + 0.1 * Eigen::MatrixXd::Identity(n, n);
}

// The mixed LCP of SolveContactImpulses with bilateral rows, checked by its optimality conditions
// alone: c = ΔtWλ − rhs is 0 on a bilateral row; λ ≥ 0, c ≥ 0 and λc = 0 on the others (to the
// solver's relative 1e-10 diagonal shift: in impulse units, c_i/(ΔtW_ii) within 1e-8 of max |λ|).
TEST(TissueGrasp, MixedLcpHoldsTheBilateralRowsAndComplementsTheOthers) {
  std::mt19937 rng(7);
  const int n = 9;
  const double dt_s = 0.01;
  int pulls = 0, separated = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const Eigen::MatrixXd W = MakeSpd(n, &rng);
    Eigen::VectorXd rhs = Eigen::VectorXd::Random(n);
    std::vector<std::uint8_t> bilateral(n, 0);
    for (int i = 0; i < 3; ++i) bilateral[3 * i] = 1;
    ContactSolveOptions options;
    options.law = ContactLaw::kUnilateral;
    Eigen::VectorXd lambda;
    const ContactSolveReport report =
        SolveContactImpulses(W, rhs, dt_s, 1, options, &lambda, nullptr, &bilateral);
    ASSERT_TRUE(report.converged) << "trial " << trial;
    const Eigen::VectorXd c = dt_s * W * lambda - rhs;
    const double tolerance = 1e-8 * lambda.lpNorm<Eigen::Infinity>();
    for (int i = 0; i < n; ++i) {
      const double slack = c[i] / (dt_s * W(i, i));  // impulse units
      if (bilateral[i]) {
        EXPECT_NEAR(slack, 0.0, tolerance) << "trial " << trial << " row " << i;
        pulls += lambda[i] < 0.0;
      } else {
        EXPECT_GE(lambda[i], 0.0);
        EXPECT_GE(slack, -tolerance);
        EXPECT_LE(std::min(lambda[i], std::abs(slack)), tolerance);
        separated += lambda[i] == 0.0;
      }
    }
  }
  // The cases the mixed law exists for did occur: bilateral rows that pull, unilateral ones
  // that let go.
  EXPECT_GT(pulls, 10);
  EXPECT_GT(separated, 10);
}

TEST(TissueGrasp, FrictionLawRefusesBilateralRows) {
  const Eigen::MatrixXd W = Eigen::MatrixXd::Identity(3, 3);
  std::vector<std::uint8_t> bilateral = {1, 0, 0};
  ContactSolveOptions options;
  options.law = ContactLaw::kFriction;
  Eigen::VectorXd lambda;
  EXPECT_THROW(SolveContactImpulses(W, Eigen::VectorXd::Ones(3), 0.01, 3, options, &lambda, nullptr,
                                    &bilateral),
               std::invalid_argument);
}

// The 1 kHz solver on rows whose first three are bilateral, in the lcp mode (no held contacts) and
// the hybrid mode, against the frame's dense mixed solve of the same W and rhs.
TEST(TissueGrasp, HapticSolverHoldsGraspRowsAsTheFrameSolveDoes) {
  std::mt19937 rng(11);
  const int n = 8, bilateral_rows = 3;
  ToolStepSystem tool;
  tool.dt_s = 1e-3;
  tool.A_v = 20.0 * Eigen::Matrix3d::Identity();
  tool.A_L = 0.5 * Eigen::Matrix3d::Identity();
  tool.M_inv_W = 1e3 * Eigen::Matrix3d::Identity();
  for (int trial = 0; trial < 20; ++trial) {
    ContactJacobian J;
    J.J_v.resize(n, 3);
    J.J_w.resize(n, 3);
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d normal = Eigen::Vector3d::Random().normalized();
      const Eigen::Vector3d lever = 0.01 * Eigen::Vector3d::Random();
      J.J_v.row(i) = -normal.transpose();
      J.J_w.row(i) = -lever.cross(normal).transpose();
    }
    const Eigen::MatrixXd W_body = 0.05 * MakeSpd(n, &rng);
    ContactRows rows;
    rows.J_v = J.J_v;
    rows.J_w = J.J_w;
    rows.W_body = W_body;
    rows.body_rhs = 0.05 * Eigen::VectorXd::Random(n);
    rows.num_bilateral_rows = bilateral_rows;
    const Eigen::Vector3d F_hat_N = Eigen::Vector3d::Random(),
                          T_hat_N_m = 0.01 * Eigen::Vector3d::Random();
    // The dense reference: W with this step's tool part, rhs = body_rhs − J_v v_free − J_ω ω_free.
    Eigen::MatrixXd W = W_body;
    AddToolDelassus(J, tool, &W);
    const Eigen::Vector3d v_free = tool.A_v.inverse() * (tool.dt_s * F_hat_N);
    const Eigen::Vector3d w_free = tool.M_inv_W * tool.A_L.inverse() * (tool.dt_s * T_hat_N_m);
    const Eigen::VectorXd rhs = rows.body_rhs - J.J_v * v_free - J.J_w * w_free;
    std::vector<std::uint8_t> bilateral(n, 0);
    for (int i = 0; i < bilateral_rows; ++i) bilateral[i] = 1;
    ContactSolveOptions options;
    Eigen::VectorXd lambda;
    ASSERT_TRUE(SolveContactImpulses(W, rhs, tool.dt_s, 1, options, &lambda, nullptr, &bilateral)
                    .converged);
    const Eigen::Vector3d F_expected_N = J.J_v.transpose() * lambda;
    for (const bool hold : {false, true}) {
      rows.lambda_frame_N = lambda.cwiseMax(0.0);  // the frame's set, as an export carries it
      rows.lambda_frame_N.head(bilateral_rows) = lambda.head(bilateral_rows);
      HapticLcpSolver solver(32, 0, hold);
      Eigen::Vector3d F_N, T_N_m;
      ASSERT_TRUE(solver.Solve(rows, tool, F_hat_N, T_hat_N_m, &F_N, &T_N_m));
      EXPECT_LE((F_N - F_expected_N).norm(), 1e-7 * std::max(1.0, F_expected_N.norm()))
          << "trial " << trial << (hold ? " hybrid" : " lcp");
      for (int i = 0; i < bilateral_rows; ++i)
        EXPECT_NEAR(solver.last_impulses()[i], lambda[i], 1e-6 * std::max(1.0, lambda.norm()));
    }
  }
}

// Two grasp rows that are one (the same row twice: W singular on them) cannot be held: the solve
// fails, so that the step renders the linear model (which holds them by a rank-revealing solve),
// rather than solve them unilaterally and let the tissue stop pulling.
TEST(TissueGrasp, DependentGraspRowsFailTheSolve) {
  ToolStepSystem tool;
  tool.dt_s = 1e-3;
  tool.A_v = 20.0 * Eigen::Matrix3d::Identity();
  tool.A_L = 0.5 * Eigen::Matrix3d::Identity();
  tool.M_inv_W = 1e3 * Eigen::Matrix3d::Identity();
  ContactRows rows;
  rows.J_v = Eigen::MatrixX3d::Zero(3, 3);
  rows.J_w = Eigen::MatrixX3d::Zero(3, 3);
  rows.J_v.row(0) = rows.J_v.row(1) = Eigen::RowVector3d(0, 0, -1);
  rows.J_v.row(2) = Eigen::RowVector3d(-1, 0, 0);
  rows.W_body = Eigen::MatrixXd::Zero(3, 3);
  rows.W_body.topLeftCorner(2, 2).setConstant(0.5);
  rows.W_body(2, 2) = 0.5;
  rows.body_rhs = Eigen::VectorXd::Constant(3, -0.01);
  rows.lambda_frame_N = Eigen::VectorXd::Zero(3);
  Eigen::Vector3d F_N, T_N_m;
  for (const bool hold : {false, true}) {
    HapticLcpSolver solver(8, 0, hold);
    rows.num_bilateral_rows = 1;  // one of the twins: it can be held
    EXPECT_TRUE(
        solver.Solve(rows, tool, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), &F_N, &T_N_m));
    rows.num_bilateral_rows = 2;  // both: no unique λ
    EXPECT_FALSE(
        solver.Solve(rows, tool, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), &F_N, &T_N_m));
    EXPECT_EQ(F_N, Eigen::Vector3d::Zero());
  }
}

// The grasp block: 4 x 4 x 2 cm, 1 cm lattice cells, bottom fixed, soft, well damped, no gravity
// (the static comparison below is then the grasp's pull alone).
struct GraspBlock {
  fem::Model model;
  fem::TetMesh mesh;
};

GraspBlock MakeGraspBlock() {
  GraspBlock block;
  block.mesh = fem::MakeBoxTetMesh({-0.02, -0.02, 0.0}, {0.02, 0.02, 0.02}, {4, 4, 2});
  fem::Material material;
  material.youngs_modulus_Pa = 20e3;
  material.poisson_ratio = 0.45;
  material.density_kg_m3 = 1000.0;
  material.rayleigh_alpha_1_s = 20.0;  // settles within the run
  material.rayleigh_beta_s = 0.01;
  const std::vector<int> bottom =
      fem::FindNodesInBox(block.mesh, {-0.03, -0.03, -0.001}, {0.03, 0.03, 0.001}, 0.0);
  block.model = fem::MakeModel(block.mesh, material, bottom);
  return block;
}

constexpr double kToolRadius_m = 0.005;
constexpr double kDt_s = 1.0 / 60.0;

// A sphere tool resting on the block's top centre, its jaws a ball of 10.5 mm about the sphere's
// lowest point: the top centre node and its four lattice neighbours 10 mm away.
VisualFrameOptions MakeGraspOptions(double max_force_N) {
  VisualFrameOptions options;
  options.dt_s = kDt_s;
  options.gravity_m_s2 = Eigen::Vector3d::Zero();
  options.coupling = CouplingParams{300.0, 3.0, 0.5, 0.005};
  options.response.solve.law = ContactLaw::kUnilateral;
  options.export_contact_rows = true;  // the 1 kHz rows, checked after each frame (RunPull)
  GraspOptions grasp;
  grasp.jaw_center_T_m = Eigen::Vector3d(0.0, 0.0, -kToolRadius_m);
  grasp.jaw_radius_m = 0.0105;
  grasp.max_force_N = max_force_N;
  options.grasp = grasp;
  return options;
}

ToolModel MakeSphereTool() {
  ToolShape sphere;
  sphere.kind = ToolShape::Kind::kSphere;
  sphere.radius_m = kToolRadius_m;
  return MakeToolModelWithMass(sphere, 0.02);
}

TEST(TissueGrasp, JawsTakeTheFreeSurfaceNodesInsideThem) {
  const GraspBlock block = MakeGraspBlock();
  VisualFrame frame(block.model, fem::FemOptions{}, Eigen::VectorXd::Zero(block.model.num_dofs()),
                    MakeSphereTool(), MakeGraspOptions(1e9));
  fem::State body = fem::MakeRestState(block.model);
  ToolState tool;
  tool.x_W_m = Eigen::Vector3d(0.0, 0.0, 0.02 + kToolRadius_m);
  DeviceState device;
  device.x_W_m = tool.x_W_m;
  device.buttons = 1;
  const VisualFrameStats stats = frame.Step(device, &body, &tool);
  // Every surface node within the ball, by a search of the rest positions: on the box's faces
  // (the node 1 cm below the top centre is inside the ball but not on the surface; none on the
  // top is fixed).
  std::vector<int> expected;
  for (int node = 0; node < block.model.num_nodes(); ++node) {
    const Eigen::Vector3d p = block.mesh.rest_positions_m.col(node);
    const bool on_surface = std::abs(std::abs(p.x()) - 0.02) < 1e-9 ||
                            std::abs(std::abs(p.y()) - 0.02) < 1e-9 ||
                            std::abs(p.z() - 0.02) < 1e-9 || std::abs(p.z()) < 1e-9;
    if (on_surface && (p - Eigen::Vector3d(0, 0, 0.02)).norm() <= 0.0105) expected.push_back(node);
  }
  EXPECT_TRUE(stats.grasp_closed_now);
  EXPECT_EQ(stats.num_grasp_taken, 5);
  ASSERT_EQ(expected.size(), 5u);
  std::vector<int> held = frame.grasp()->held_nodes();
  std::sort(held.begin(), held.end());
  EXPECT_EQ(held, expected);
  // Three grasp rows a node, none of the tool's own contacts on them.
  int grasp_rows = 0;
  for (const Contact& contact : frame.contacts()) {
    grasp_rows += contact.bilateral;
    if (contact.bilateral) continue;
    for (int k = 0; k < kMaxContactNodes && contact.nodes[k] >= 0; ++k)
      EXPECT_FALSE(frame.grasp()->Holds(contact.nodes[k]));
  }
  EXPECT_EQ(grasp_rows, 15);
  // The button released: open, nothing held, no grasp rows.
  device.buttons = 0;
  frame.Step(device, &body, &tool);
  EXPECT_TRUE(frame.grasp()->held_nodes().empty());
  for (const Contact& contact : frame.contacts()) EXPECT_FALSE(contact.bilateral);
}

// K at rest (rotations I), whole (both triangles), over every dof.
Eigen::SparseMatrix<double> AssembleRestStiffness(const fem::Model& model) {
  const fem::StiffnessAssembler assembler(model);
  Eigen::SparseMatrix<double> K = assembler.MakeMatrix();
  assembler.Assemble(
      model, std::vector<Eigen::Matrix3d>(model.num_tets(), Eigen::Matrix3d::Identity()), 1.0, &K);
  return K.selfadjointView<Eigen::Lower>();
}

// Linear statics with the grasped nodes' displacement imposed: K_ff u_f = −K_fg u_g on the nodes
// neither fixed nor grasped, then the force the grasp must put on the grasped nodes to hold them
// there, Σ_g (K u)_g (N, world).
Eigen::Vector3d SolveDirichletReaction(const fem::Model& model, const std::vector<int>& grasped,
                                       const Eigen::VectorXd& u_grasped_m) {
  const Eigen::SparseMatrix<double> K = AssembleRestStiffness(model);
  const int n = model.num_dofs();
  std::vector<int> role(n, 0);  // 0 free, 1 fixed, 2 grasped
  for (int d = 0; d < n; ++d) role[d] = model.dof_is_fixed[d] ? 1 : 0;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
  for (size_t g = 0; g < grasped.size(); ++g)
    for (int a = 0; a < 3; ++a) {
      role[3 * grasped[g] + a] = 2;
      u[3 * grasped[g] + a] = u_grasped_m[3 * static_cast<Eigen::Index>(g) + a];
    }
  std::vector<int> free, index_of(n, -1);
  for (int d = 0; d < n; ++d)
    if (role[d] == 0) {
      index_of[d] = static_cast<int>(free.size());
      free.push_back(d);
    }
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(free.size()));
  for (int c = 0; c < K.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, c); it; ++it) {
      const int r = static_cast<int>(it.row());
      if (role[r] != 0) continue;
      if (role[c] == 0) entries.emplace_back(index_of[r], index_of[c], it.value());
      if (role[c] == 2) rhs[index_of[r]] -= it.value() * u[c];
    }
  Eigen::SparseMatrix<double> K_ff(rhs.size(), rhs.size());
  K_ff.setFromTriplets(entries.begin(), entries.end());
  const Eigen::VectorXd u_f = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>(K_ff).solve(rhs);
  for (size_t k = 0; k < free.size(); ++k) u[free[k]] = u_f[static_cast<Eigen::Index>(k)];
  const Eigen::VectorXd f = K * u;
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (int node : grasped) total += f.segment<3>(3 * node);
  return total;
}

// Runs the grasp block: the jaws close on the top centre at rest, then the device lifts by
// lift_m over 0.5 s and holds for `hold_s`. Returns the last frame's statistics.
struct PullRun {
  VisualFrameStats last;
  int slipped = 0;
  double peak_grip_pull_N = 0.0;
};

PullRun RunPull(VisualFrame* frame, fem::State* body, ToolState* tool, double lift_m,
                double hold_s) {
  DeviceState device;
  device.x_W_m = Eigen::Vector3d(0.0, 0.0, 0.02 + kToolRadius_m);
  *tool = ToolState{};
  tool->x_W_m = device.x_W_m;
  device.buttons = 1;
  PullRun run;
  const int frames = static_cast<int>(std::lround((0.5 + hold_s) / kDt_s));
  for (int k = 0; k < frames; ++k) {
    const double t_s = (k + 1) * kDt_s;
    device.x_W_m.z() = 0.02 + kToolRadius_m + lift_m * std::min(1.0, t_s / 0.5);
    run.last = frame->Step(device, body, tool);
    run.slipped += run.last.num_grasp_slipped;
    // The rows handed to the 1 kHz step hold the points still held, not those that slipped at
    // this frame's end.
    EXPECT_EQ(frame->contact_rows().num_bilateral_rows, 3 * run.last.num_grasped) << t_s;
    run.peak_grip_pull_N = std::max(run.peak_grip_pull_N, -frame->contact_force_N().z());
  }
  return run;
}

// A grasped top pulled up and held: at rest, the grasp's force on the body equals the reaction of
// the linear static solve with those nodes' displacement imposed, and the coupling carries it to
// the device. Two device lifts, 0.4 and 2 mm (the nodes rise ~0.08 and ~0.4 mm, up to 2 % of the
// block's height): the corotational body departs from linear statics in proportion to the
// displacement, so the bound is 0.5 % for the small lift and 2 % for the larger.
TEST(TissueGrasp, GraspedBlockPulledUpFeelsTheStaticDirichletReaction) {
  const GraspBlock block = MakeGraspBlock();
  for (const auto& [lift_m, tolerance] : {std::pair{4e-4, 0.005}, std::pair{2e-3, 0.02}}) {
    VisualFrame frame(block.model, fem::FemOptions{}, Eigen::VectorXd::Zero(block.model.num_dofs()),
                      MakeSphereTool(), MakeGraspOptions(1e9));
    fem::State body = fem::MakeRestState(block.model);
    ToolState tool;
    const PullRun run = RunPull(&frame, &body, &tool, lift_m, 3.0);
    ASSERT_EQ(run.slipped, 0);
    const std::vector<int>& held = frame.grasp()->held_nodes();
    ASSERT_EQ(held.size(), 5u);
    EXPECT_LT(body.v_m_s.lpNorm<Eigen::Infinity>(), 1e-6) << "not at rest";
    // The grasp's force on the body: each row's λ along its normal.
    Eigen::Vector3d grasp_on_body_N = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < frame.contacts().size(); ++i)
      if (frame.contacts()[i].bilateral)
        grasp_on_body_N += frame.impulses()[static_cast<Eigen::Index>(i)] * frame.contacts()[i].n_W;
    Eigen::VectorXd u_grasped(3 * static_cast<Eigen::Index>(held.size()));
    for (size_t g = 0; g < held.size(); ++g)
      u_grasped.segment<3>(3 * static_cast<Eigen::Index>(g)) =
          body.x_m.segment<3>(3 * held[g]) - block.mesh.rest_positions_m.col(held[g]);
    const Eigen::Vector3d reaction_N = SolveDirichletReaction(block.model, held, u_grasped);
    const double coupling_N = 300.0 * (0.02 + kToolRadius_m + lift_m - tool.x_W_m.z());
    std::printf(
        "grasped top lifted %.3f mm: grasp on body %.5f N, Dirichlet reaction %.5f N "
        "(%+.2f %%), coupling %.5f N\n",
        1e3 * u_grasped.segment<3>(0).z(), grasp_on_body_N.z(), reaction_N.z(),
        100.0 * (grasp_on_body_N.z() / reaction_N.z() - 1.0), coupling_N);
    EXPECT_GT(reaction_N.z(), 0.0);  // the body is pulled up
    EXPECT_NEAR(grasp_on_body_N.z(), reaction_N.z(), tolerance * reaction_N.z());
    EXPECT_LT((grasp_on_body_N - reaction_N).head<2>().norm(), tolerance * reaction_N.z());
    // The device holds it through the coupling (the tool at rest: no other force on it).
    EXPECT_NEAR(coupling_N, grasp_on_body_N.z(), 1e-3 * grasp_on_body_N.z());
  }
}

// A grip limit below the pull the lift needs: the points slip out, and the tool, free again, rises
// to the device (the coupling's force back to zero).
TEST(TissueGrasp, GripOverItsLimitSlipsAndFreesTheTool) {
  const GraspBlock block = MakeGraspBlock();
  // The same lift held with an unlimited grip: the pull it needs, to set the limit against.
  double held_pull_N = 0.0;
  {
    VisualFrame frame(block.model, fem::FemOptions{}, Eigen::VectorXd::Zero(block.model.num_dofs()),
                      MakeSphereTool(), MakeGraspOptions(1e9));
    fem::State body = fem::MakeRestState(block.model);
    ToolState tool;
    held_pull_N = RunPull(&frame, &body, &tool, 2e-3, 1.0).peak_grip_pull_N;
  }
  ASSERT_GT(held_pull_N, 0.0);
  VisualFrame frame(block.model, fem::FemOptions{}, Eigen::VectorXd::Zero(block.model.num_dofs()),
                    MakeSphereTool(), MakeGraspOptions(0.1 * held_pull_N));
  fem::State body = fem::MakeRestState(block.model);
  ToolState tool;
  const PullRun run = RunPull(&frame, &body, &tool, 2e-3, 1.0);
  std::printf(
      "pull with unlimited grip %.4f N; with a limit of %.4f N a point: %d slipped, "
      "%d still held, contact force %.2e N at the end\n",
      held_pull_N, 0.1 * held_pull_N, run.slipped, run.last.num_grasped,
      frame.contact_force_N().norm());
  EXPECT_EQ(run.slipped, 5);
  EXPECT_EQ(run.last.num_grasped, 0);
  EXPECT_LT(frame.contact_force_N().norm(), 1e-6);
  EXPECT_NEAR(tool.x_W_m.z(), 0.02 + kToolRadius_m + 2e-3, 1e-5);
}

}  // namespace
}  // namespace hapsim::contact
