// The whole visual frame on small scenes, against physics that does not depend on the code:
// a tool at rest carries its weight; Newton's impact law with e = 0 and e = 1 against a rigid
// wall; a tool at 10 m/s does not tunnel through a 1 cm slab.
#include "contact/visual_frame.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <memory>
#include <vector>

#include "contact/linear_contact_model.h"
#include "core/tool_integrator.h"
#include "fem/lattice_mesher.h"
#include "fem/time_stepper.h"

namespace hapsim::contact {
namespace {

// A 10 x 10 cm slab of thickness `thickness_m`, top face at z = 0; bottom fixed, or all fixed.
fem::Model MakeSlab(double thickness_m, double youngs_modulus_Pa, bool all_fixed) {
  const fem::TetMesh mesh =
      fem::MakeBoxTetMesh({-0.05, -0.05, -thickness_m}, {0.05, 0.05, 0.0}, {8, 8, 2});
  fem::Material material;
  material.youngs_modulus_Pa = youngs_modulus_Pa;
  material.poisson_ratio = 0.3;
  const double top_z = all_fixed ? 1.0 : -thickness_m + 1e-9;
  return fem::MakeModel(mesh, material,
                        fem::FindNodesInBox(mesh, {-1, -1, -1}, {1, 1, top_z}, 0.0));
}

ToolModel MakeBoxTool(double mass_kg) {
  ToolShape shape;
  shape.kind = ToolShape::Kind::kBox;
  shape.half_extents_m = Eigen::Vector3d(0.02, 0.02, 0.01);  // 4 x 4 cm face: 3 x 3 lattice nodes
  return MakeToolModelWithMass(shape, mass_kg);
}

VisualFrameOptions MakeOptions(double dt_s, ContactLaw law, double restitution) {
  VisualFrameOptions options;
  options.dt_s = dt_s;
  options.response.solve.law = law;
  options.response.solve.max_iterations = 5000;
  options.response.restitution = restitution;
  return options;  // no coupling: k = b = 0
}

// Deepest penetration of any body node into the tool, m (≤ 0 when none).
double CalcPenetration(const VisualFrame& frame, const fem::State& body, const ToolState& tool) {
  const Eigen::Isometry3d X_TW = CalcPose(tool).inverse();
  const ToolDistanceField field(frame.tool_model().shape);
  double deepest_m = 0.0;
  for (Eigen::Index n = 0; n < body.x_m.size() / 3; ++n)
    deepest_m = std::min(deepest_m,
                         field.Calc(X_TW * Eigen::Vector3d(body.x_m.segment<3>(3 * n))).distance_m);
  return -deepest_m;
}

TEST(VisualFrame, ToolAtRestOnAStiffBodyCarriesItsWeight) {
  const fem::Model body = MakeSlab(0.02, 1e8, false);  // 100 MPa: sag under the tool ≪ 0.1 mm
  const double mass_kg = 0.2;
  VisualFrame frame(body, fem::FemOptions{}, fem::CalcGravityForce(body, {0, 0, -9.81}),
                    MakeBoxTool(mass_kg), MakeOptions(1.0 / 60.0, ContactLaw::kUnilateral, 0.0));
  fem::State body_state = fem::MakeRestState(body);
  ToolState tool;
  tool.x_W_m = Eigen::Vector3d(0.0, 0.0, 0.01);  // resting on the top face
  for (int k = 0; k < 120; ++k) frame.Step(DeviceState{}, &body_state, &tool);
  const double weight_N = mass_kg * 9.81;
  EXPECT_NEAR(frame.contact_force_N().z(), weight_N, 1e-3 * weight_N);
  // Lateral force only from the slightly tilted faces under the corners of the box: small.
  EXPECT_LT(frame.contact_force_N().head<2>().norm(), 1e-4 * weight_N);
  EXPECT_LE(CalcPenetration(frame, body_state, tool), 1e-4);
  EXPECT_LT(tool.v_W_m_s.norm(), 1e-4);
}

// The sanity pass (stage 7) moves every node the response left inside the tool onto its surface,
// frame after frame: a box pushed 4 mm into a slab with no stabilisation (β = 0: the response
// only stops the nodes approaching), then 3 mm further. The depth is checked against the tool's
// distance field node by node.
TEST(VisualFrame, SanityPassMovesTheNodesLeftInsideOutEveryFrame) {
  const fem::Model body = MakeSlab(0.02, 5e4, false);
  VisualFrameOptions options = MakeOptions(1.0 / 60.0, ContactLaw::kUnilateral, 0.0);
  options.gravity_m_s2.setZero();
  options.response.stabilization_beta = 0.0;
  VisualFrame frame(body, fem::FemOptions{}, Eigen::VectorXd::Zero(body.num_dofs()),
                    MakeBoxTool(0.2), options);
  fem::State body_state = fem::MakeRestState(body);
  ToolState tool;
  for (const double z_m : {0.01 - 0.004, 0.01 - 0.007}) {
    tool.x_W_m = Eigen::Vector3d(0.0, 0.0, z_m);
    tool.v_W_m_s.setZero();
    ASSERT_GT(CalcPenetration(frame, body_state, tool), 0.002);
    const VisualFrameStats stats = frame.Step(DeviceState{}, &body_state, &tool);
    EXPECT_GE(stats.num_sanity_corrections, 9);  // the 3 x 3 nodes under the box's face at least
    EXPECT_LE(CalcPenetration(frame, body_state, tool), options.sanity_tolerance_m);
  }
}

// A 0.2 kg box set on `slab`'s top face and left there for `frames` frames under gravity.
std::unique_ptr<VisualFrame> SettleBoxOnSlab(const fem::Model& slab,
                                             const VisualFrameOptions& options, int frames,
                                             ToolState* tool) {
  auto frame = std::make_unique<VisualFrame>(
      slab, fem::FemOptions{}, fem::CalcGravityForce(slab, {0, 0, -9.81}), MakeBoxTool(0.2),
      options);
  fem::State slab_state = fem::MakeRestState(slab);
  tool->x_W_m = Eigen::Vector3d(0.0, 0.0, 0.01);
  for (int k = 0; k < frames; ++k) frame->Step(DeviceState{}, &slab_state, tool);
  return frame;
}

// The linear model's body compliance at the haptic step (ModelComplianceStep::kHaptic). With
// A(Δt) = M + Δt D + Δt² K, A(Δt_v) − A(Δt_h) ⪰ 0 for Δt_h < Δt_v, so the body compliance
// J A⁻¹ Jᵀ at the haptic step is at least the visual one: the body yields more, and less of a
// push on the tool (∂F_c/∂F̂) reaches the contact. When the two steps agree the two models are
// the same.
LinearContactModel ModelOfToolOnSoftSlab(ModelComplianceStep step, double haptic_dt_s) {
  const fem::Model body = MakeSlab(0.02, 5e4, false);
  VisualFrameOptions options = MakeOptions(1.0 / 30.0, ContactLaw::kUnilateral, 0.0);
  options.haptic_dt_s = haptic_dt_s;
  options.model_compliance_step = step;
  ToolState tool;
  return SettleBoxOnSlab(body, options, 10, &tool)->linear_model();
}

TEST(VisualFrame, HapticStepComplianceYieldsMoreAndAgreesAtEqualSteps) {
  const double dt_s = 1.0 / 30.0;
  const LinearContactModel visual = ModelOfToolOnSoftSlab(ModelComplianceStep::kVisual, 1e-3);
  const LinearContactModel haptic = ModelOfToolOnSoftSlab(ModelComplianceStep::kHaptic, 1e-3);
  // The tool rests on the slab, its contacts active: most of a push reaches them.
  ASSERT_LT(visual.dFc_dF(2, 2), -0.5);
  std::printf("dFc/dF zz: visual-step W %.6f, haptic-step W %.6f\n", visual.dFc_dF(2, 2),
              haptic.dFc_dF(2, 2));
  EXPECT_LT(std::abs(haptic.dFc_dF(2, 2)), std::abs(visual.dFc_dF(2, 2)) * (1.0 - 1e-3));
  const LinearContactModel visual_equal = ModelOfToolOnSoftSlab(ModelComplianceStep::kVisual, dt_s);
  const LinearContactModel haptic_equal = ModelOfToolOnSoftSlab(ModelComplianceStep::kHaptic, dt_s);
  EXPECT_NEAR((haptic_equal.dFc_dF - visual_equal.dFc_dF).norm(), 0.0,
              1e-9 * visual_equal.dFc_dF.norm());
  EXPECT_NEAR((haptic_equal.F_c0_N - visual_equal.F_c0_N).norm(), 0.0,
              1e-9 * visual_equal.F_c0_N.norm());
}

// The linear model rebuilt from the rows the frame exports (every contact coupled: lcp_reach_m_s
// 0), by the formula of linear_contact_model.h on the rows the frame found active (λ > 0), with
// the tool's step system at the haptic Δt and W's diagonal scaled by `diagonal_factor`.
LinearContactModel RebuildModelFromRows(const VisualFrame& frame, const ToolState& tool,
                                        const VisualFrameOptions& options,
                                        double diagonal_factor) {
  const ContactRows& rows = frame.contact_rows();
  std::vector<Eigen::Index> active;
  for (Eigen::Index i = 0; i < rows.num_rows(); ++i)
    if (rows.lambda_frame_N[i] > 0.0) active.push_back(i);
  const Eigen::Index n = static_cast<Eigen::Index>(active.size());
  ContactJacobian J;
  J.J_v.resize(n, 3);
  J.J_w.resize(n, 3);
  Eigen::MatrixXd W_body(n, n);
  Eigen::VectorXd body_rhs(n);
  for (Eigen::Index r = 0; r < n; ++r) {
    J.J_v.row(r) = rows.J_v.row(active[r]);
    J.J_w.row(r) = rows.J_w.row(active[r]);
    body_rhs[r] = rows.body_rhs[active[r]];
    for (Eigen::Index c = 0; c < n; ++c) W_body(r, c) = rows.W_body(active[r], active[c]);
  }
  const CouplingWrench no_coupling;  // the options' coupling: k = b = 0
  const ToolStepSystem haptic = CalcToolStepSystem(frame.tool_model(), tool, no_coupling,
                                                   options.gravity_m_s2, options.haptic_dt_s);
  Eigen::MatrixXd W = CalcToolDelassus(J, haptic) + W_body;
  W.diagonal() *= diagonal_factor;
  return MakeLinearContactModel(J, W, haptic, body_rhs);
}

// The equality law's compliance reaches the linear model (contact_solver.h: the frame's solve
// holds W_ii (1 + ε), and the model must hold the same law or it answers a different problem
// between frames), and only that law's: ε = 0.5, so that a model built the other way differs by
// far more than the tolerance, under the equality and the unilateral law.
TEST(VisualFrame, EqualityLawModelHoldsTheLawsCompliance) {
  const fem::Model body = MakeSlab(0.02, 5e4, false);
  for (const ContactLaw law : {ContactLaw::kEquality, ContactLaw::kUnilateral}) {
    SCOPED_TRACE(ToString(law));
    VisualFrameOptions options = MakeOptions(1.0 / 30.0, law, 0.0);
    options.response.solve.equality_compliance = 0.5;
    options.haptic_dt_s = 1e-3;
    options.model_compliance_step = ModelComplianceStep::kVisual;
    options.export_contact_rows = true;
    ToolState tool;
    const std::unique_ptr<VisualFrame> frame = SettleBoxOnSlab(body, options, 6, &tool);
    const double held = law == ContactLaw::kEquality
                            ? 1.0 + options.response.solve.equality_compliance
                            : 1.0;
    const LinearContactModel expected = RebuildModelFromRows(*frame, tool, options, held);
    const LinearContactModel other =
        RebuildModelFromRows(*frame, tool, options, held == 1.0 ? 1.5 : 1.0);
    const LinearContactModel& model = frame->linear_model();
    ASSERT_GT(expected.num_contacts, 3) << "precondition: the box rests on several contacts";
    EXPECT_EQ(model.num_contacts, expected.num_contacts);
    EXPECT_LT((model.dFc_dF - expected.dFc_dF).norm(), 1e-9 * expected.dFc_dF.norm());
    EXPECT_LT((model.dTc_dT - expected.dTc_dT).norm(), 1e-9 * expected.dTc_dT.norm());
    EXPECT_LT((model.F_c0_N - expected.F_c0_N).norm(), 1e-9 * expected.F_c0_N.norm());
    EXPECT_GT((other.dFc_dF - expected.dFc_dF).norm(), 1e-2 * expected.dFc_dF.norm())
        << "precondition: the compliance changes the model";
  }
}

// The lcp rows that travel (issue 13 item 5): with lcp_reach_m_s the frame exports every contact
// of the all-rows export, whole (three rows each with friction, and their μ), bit for bit: first,
// in order, those that are active (λ_n > 0) or that the tool's present approach plus the reach
// engages while the other contacts push as the frame had them push (shortfall s_i = (J_v,i v +
// J_ω,i ω) − (r_i − h_i) < v_reach, r_i the all-coupled target and h_i = Δt_h (W_body λ_vis)_i its
// hold-back), with their W_body coupling; then the others by s_i ascending, each with its own
// block of W_body and zeros to every other row, and the target r_i − h_i. With lcp_max_rows the
// uncoupled ones nearest to engaging fill what room is left. The frame itself is unchanged. (On
// this slab counting h_i in s_i would couple no other contact, so the test does not tell the two
// rules apart; on block_press in the hybrid mode it coupled 175 contacts instead of 74,
// docs/BENCHMARKS.md "eighth pass".)
TEST(VisualFrame, LcpRowsCoupleTheActiveAndTheReachableContacts) {
  const fem::Model body = MakeSlab(0.02, 5e4, false);
  for (const ContactLaw law : {ContactLaw::kUnilateral, ContactLaw::kFriction}) {
    SCOPED_TRACE(ToString(law));
    const int per = law == ContactLaw::kFriction ? 3 : 1;
    ToolState tool_all;
    const auto run = [&](double reach_m_s, int max_rows, ToolState* tool) {
      VisualFrameOptions options = MakeOptions(1.0 / 30.0, law, 0.0);
      options.response.solve.friction_coefficient = 0.4;
      options.haptic_dt_s = 1e-3;
      options.export_contact_rows = true;
      options.lcp_reach_m_s = reach_m_s;
      options.lcp_max_rows = max_rows;
      options.detection.margin_m = 0.003;  // candidates up to 3 mm away: some cannot engage
      auto frame = std::make_unique<VisualFrame>(body, fem::FemOptions{},
                                                 fem::CalcGravityForce(body, {0, 0, -9.81}),
                                                 MakeBoxTool(0.2), options);
      fem::State body_state = fem::MakeRestState(body);
      tool->x_W_m = Eigen::Vector3d(0.0, 0.0, 0.01);
      tool->q_WT = Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitX());  // tilted: gaps of all sizes
      tool->v_W_m_s = Eigen::Vector3d(0.01, 0.0, -0.005);              // moving: it counts
      for (int k = 0; k < 6; ++k) frame->Step(DeviceState{}, &body_state, tool);
      return frame;
    };
    const double reach_m_s = 0.005;
    const auto all = run(0.0, 0, &tool_all);
    const ContactRows& a = all->contact_rows();
    const Eigen::Vector3d w = CalcAngularVelocity(all->tool_model(), tool_all);
    std::vector<int> coupled, uncoupled;  // contacts of `a`
    std::vector<double> shortfall(a.num_rows() / per);
    for (int i = 0; i < a.num_rows() / per; ++i) {
      const int n = per * i;
      const double held = 1e-3 * a.W_body.row(n).dot(a.lambda_frame_N);
      const double tool_separating = a.J_v.row(n).dot(tool_all.v_W_m_s) + a.J_w.row(n).dot(w);
      shortfall[i] = tool_separating - (a.body_rhs[n] - held);
      const bool loaded = a.lambda_frame_N[n] > 0.0;
      (loaded || shortfall[i] < reach_m_s ? coupled : uncoupled).push_back(i);
    }
    std::stable_sort(uncoupled.begin(), uncoupled.end(),
                     [&](int i, int j) { return shortfall[i] < shortfall[j]; });
    int active = 0;
    for (int i = 0; i < a.num_rows() / per; ++i) active += a.lambda_frame_N[per * i] > 0.0;
    const int num_coupled = static_cast<int>(coupled.size());
    std::printf("%s: %d candidate contacts, %d active, %d coupled\n", ToString(law),
                a.num_rows() / per, active, num_coupled);
    ASSERT_GT(active, 0);
    ASSERT_GT(num_coupled, active) << "precondition: an inactive contact is coupled";
    ASSERT_GT(uncoupled.size(), 2u) << "precondition: uncoupled contacts to choose from";
    EXPECT_EQ(a.num_uncoupled_rows, 0);
    for (const int max_rows : {0, per * (num_coupled + 2)}) {
      SCOPED_TRACE(max_rows);
      ToolState tool_cut;
      const auto cut = run(reach_m_s, max_rows, &tool_cut);
      const ContactRows& c = cut->contact_rows();
      EXPECT_EQ(cut->contact_force_N(), all->contact_force_N());  // the frame is the same
      std::vector<int> order = coupled;
      order.insert(order.end(), uncoupled.begin(),
                   max_rows == 0 ? uncoupled.end() : uncoupled.begin() + 2);
      const int num = static_cast<int>(order.size());
      double largest_held = 0.0;  // over the uncoupled rows, m/s
      ASSERT_EQ(c.num_rows(), per * num);
      EXPECT_EQ(c.rows_per_contact, per);
      EXPECT_EQ(c.num_uncoupled_rows, per * (num - num_coupled));
      for (int k = 0; k < num; ++k) {
        if (per == 3) {
          EXPECT_EQ(c.friction_coefficient[k], a.friction_coefficient[order[k]]);
        }
        for (int d = 0; d < per; ++d) {
          const int r = per * k + d, i = per * order[k] + d;
          EXPECT_EQ(c.J_v.row(r), a.J_v.row(i)) << r;
          EXPECT_EQ(c.J_w.row(r), a.J_w.row(i)) << r;
          if (k < num_coupled) {
            EXPECT_EQ(c.body_rhs[r], a.body_rhs[i]) << r;
          } else {  // without the hold-back of the other contacts' frame force
            const double held = 1e-3 * a.W_body.row(i).dot(a.lambda_frame_N);
            EXPECT_NEAR(c.body_rhs[r], a.body_rhs[i] - held, 1e-12 * std::abs(a.body_rhs[i]))
                << r;
            largest_held = std::max(largest_held, std::abs(held));
          }
          EXPECT_EQ(c.lambda_frame_N[r], a.lambda_frame_N[i]) << r;
          for (int q = 0; q < num; ++q) {
            const bool couples = (k < num_coupled && q < num_coupled) || k == q;
            for (int e = 0; e < per; ++e) {
              EXPECT_EQ(c.W_body(r, per * q + e), couples ? a.W_body(i, per * order[q] + e) : 0.0)
                  << r << ", " << per * q + e;
            }
          }
        }
      }
      EXPECT_GT(largest_held, 1e-6) << "precondition: the hold-back matters";
    }
  }
}

// Rigid wall (every node fixed), impact at 1 m/s. Contacts are speculative: in the first frame the
// tool may only close the 2 mm gap (it ends on the wall, still at −gap/Δt with e = 0); the
// impact law shows once contact is made, so the velocity is read after the second frame.
double ImpactVelocity(double restitution) {
  const fem::Model wall = MakeSlab(0.02, 1e6, true);
  VisualFrameOptions options = MakeOptions(1e-2, ContactLaw::kUnilateral, restitution);
  options.gravity_m_s2.setZero();
  VisualFrame frame(wall, fem::FemOptions{}, Eigen::VectorXd::Zero(wall.num_dofs()),
                    MakeBoxTool(0.1), options);
  fem::State wall_state = fem::MakeRestState(wall);
  ToolState tool;
  tool.x_W_m = Eigen::Vector3d(0.0, 0.0, 0.01 + 0.002);  // 2 mm above, closing 10 mm per frame
  tool.v_W_m_s = Eigen::Vector3d(0.0, 0.0, -1.0);
  for (int k = 0; k < 2; ++k) {
    frame.Step(DeviceState{}, &wall_state, &tool);
    EXPECT_GE(tool.x_W_m.z() - 0.01, -1e-9) << "the tool entered the wall";
  }
  return tool.v_W_m_s.z();
}

TEST(VisualFrame, ImpactFollowsNewtonsLawOfRestitution) {
  // Against an immovable wall the post-impact velocity is −e times the approach velocity.
  EXPECT_NEAR(ImpactVelocity(0.0), 0.0, 1e-6);
  EXPECT_NEAR(ImpactVelocity(1.0), 1.0, 1e-6);
}

TEST(VisualFrame, FastToolDoesNotTunnelThroughAThinSlab) {
  const fem::Model slab = MakeSlab(0.01, 1e9, false);  // 1 cm thick, stiff: its surface stays put
  VisualFrameOptions options = MakeOptions(1.0 / 60.0, ContactLaw::kUnilateral, 0.0);
  options.gravity_m_s2.setZero();
  VisualFrame frame(slab, fem::FemOptions{}, Eigen::VectorXd::Zero(slab.num_dofs()),
                    MakeBoxTool(0.1), options);
  fem::State slab_state = fem::MakeRestState(slab);
  ToolState tool;
  tool.x_W_m = Eigen::Vector3d(0.0, 0.0, 0.01 + 0.05);  // 5 cm above; moves 16.7 cm per frame
  tool.v_W_m_s = Eigen::Vector3d(0.0, 0.0, -10.0);
  // Frame 1 closes the 5 cm gap exactly (speculative contact); frame 2 stops the tool. Without
  // swept detection it would be 11.7 cm below the top face, under the slab, after frame 1.
  for (int k = 0; k < 2; ++k) {
    frame.Step(DeviceState{}, &slab_state, &tool);
    EXPECT_NEAR(tool.x_W_m.z() - 0.01, 0.0, 1e-4) << "frame " << k;  // bottom face on top face
  }
  EXPECT_GT(tool.v_W_m_s.z(), -1e-3);
}

}  // namespace
}  // namespace hapsim::contact
