// Contact between the body's objects (contact/body_body_contacts.h, issue 28 item 2), against
// statics and geometry the contact code does not compute: a block resting on another carries
// exactly its weight through their contact (ρ V g, from its size alone) and rests on its surface;
// the objects are the models merged into the body; a row measures the gap's rate between them.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "contact/body_body_contacts.h"
#include "contact/contact_jacobian.h"
#include "contact/visual_frame.h"
#include "fem/lattice_mesher.h"
#include "fem/model.h"
#include "fem/time_stepper.h"
#include "tests/contact/rigid_object_fixtures.h"

namespace hapsim::contact {
namespace {

constexpr double kGravity_m_s2 = 9.81;
constexpr double kDensity_kg_m3 = 1000.0;

fem::Material MakeSoft(double youngs_modulus_Pa) {
  fem::Material material;
  material.youngs_modulus_Pa = youngs_modulus_Pa;
  material.poisson_ratio = 0.45;
  material.density_kg_m3 = kDensity_kg_m3;
  material.rayleigh_alpha_1_s = 10.0;  // settles within the run
  return material;
}

// A 4 x 4 x 2 cm block fixed at its base (z = 0), or whole, and on it a free 2 x 2 x 1 cm block
// whose bottom is `gap_m` above the lower block's top (z = 2 cm): one FEM system of two objects.
fem::Model MakeStack(double gap_m, bool lower_fixed_whole = false) {
  const fem::TetMesh lower =
      fem::MakeBoxTetMesh({-0.02, -0.02, 0.0}, {0.02, 0.02, 0.02}, {4, 4, 2});
  const fem::TetMesh upper =
      fem::MakeBoxTetMesh({-0.01, -0.01, 0.02 + gap_m}, {0.01, 0.01, 0.03 + gap_m}, {3, 3, 2});
  const std::vector<int> base = fem::FindNodesInBox(
      lower, {-0.03, -0.03, -0.001}, {0.03, 0.03, lower_fixed_whole ? 0.03 : 0.001}, 0.0);
  return fem::MergeModels(
      {fem::MakeModel(lower, MakeSoft(30e3), base), fem::MakeModel(upper, MakeSoft(20e3), {})});
}

// The frame of the stack's tests: a small sphere tool (kept far above), the law and gravity given.
VisualFrameOptions MakeStackOptions(double dt_s, const Eigen::Vector3d& gravity_m_s2,
                                    ContactLaw law) {
  VisualFrameOptions options;
  options.dt_s = dt_s;
  options.gravity_m_s2 = gravity_m_s2;
  options.coupling = CouplingParams{100.0, 1.0, 0.1, 0.001};
  options.response.solve.law = law;
  return options;
}

ToolModel MakeSphereTool() { return fixtures::MakeSphereTool(0.005, 0.01); }

// Runs `frames` frames of the stack from rest with the tool parked far above, out of the way.
fem::State RunWithTheToolAway(VisualFrame* frame, const fem::Model& stack, int frames) {
  ToolState tool;
  tool.x_W_m = Eigen::Vector3d(0.0, 0.0, 0.5);
  DeviceState device;
  device.x_W_m = tool.x_W_m;
  fem::State body = fem::MakeRestState(stack);
  for (int k = 0; k < frames; ++k) frame->Step(device, &body, &tool);
  return body;
}

TEST(BodyBodyContact, ObjectsAreTheMergedModels) {
  const fem::Model stack = MakeStack(0.001);
  const BodyBodyContacts contacts(stack, 0.001);
  ASSERT_EQ(contacts.num_objects(), 2);
  // The lower block's 5 x 5 x 3 lattice nodes come first.
  for (int node = 0; node < stack.num_nodes(); ++node)
    EXPECT_EQ(contacts.object_of_node(node), node < 75 ? 0 : 1) << node;
}

// Each row's J_u u̇ is the rate of its gap, by finite differences of the gap under a velocity
// field u̇ applied for a short time (the gap recomputed from the moved positions, as the detection
// would compute it: the node against the face's moved plane at the same barycentric weights).
TEST(BodyBodyContact, RowsMeasureTheGapsRate) {
  const fem::Model stack = MakeStack(0.0005);
  const BodyBodyContacts finder(stack, 0.001);
  const Eigen::VectorXd x = stack.rest_positions_m;
  std::vector<Contact> contacts;
  finder.AddContacts(x, x, &contacts);
  ASSERT_GT(contacts.size(), 20u);
  const ContactJacobian J = CalcContactJacobian(contacts, Eigen::Vector3d::Zero(), 1,
                                                stack.num_dofs(), stack.dof_is_fixed);
  EXPECT_EQ(J.J_v.norm(), 0.0);  // no tool
  const Eigen::VectorXd u_dot =
      Eigen::VectorXd::Random(stack.num_dofs())
          .cwiseProduct(Eigen::Map<const Eigen::Array<std::uint8_t, Eigen::Dynamic, 1>>(
                            stack.dof_is_fixed.data(), stack.num_dofs())
                            .cast<double>()
                            .matrix()
                            .unaryExpr([](double fixed) { return 1.0 - fixed; }));
  const double h = 1e-7;
  const Eigen::VectorXd x_moved = x + h * u_dot;
  const Eigen::VectorXd rate = J.J_u * u_dot;
  for (size_t i = 0; i < contacts.size(); ++i) {
    const Contact& c = contacts[i];
    Eigen::Vector3d node = x_moved.segment<3>(3 * c.nodes[0]), face = Eigen::Vector3d::Zero();
    for (int k = 1; k < 4; ++k) face -= c.weights[k] * x_moved.segment<3>(3 * c.nodes[k]);
    const double gap_moved = (node - face).dot(c.n_W);  // the normal held: J leaves its turn out
    EXPECT_NEAR((gap_moved - c.gap_m) / h, rate[static_cast<Eigen::Index>(i)], 1e-6) << i;
    EXPECT_NEAR(c.gap_m, 0.0005, 1e-12) << i;  // the blocks' faces are 0.5 mm apart
  }
}

// The upper block dropped from 1 mm settles on the lower: the contact carries its weight
// ρ V g = 1000 · 4e-6 · 9.81 = 0.0392 N (the sum of λ n over its contacts, with the sign of its
// side), and its bottom rests on the lower block's top. The lower block fixed at its base, or
// whole (no free node: a surface to rest on all the same).
class StackedBlock : public testing::TestWithParam<bool> {};

TEST_P(StackedBlock, CarriesExactlyItsWeight) {
  const fem::Model stack = MakeStack(0.001, GetParam());
  const VisualFrameOptions options =
      MakeStackOptions(1.0 / 60.0, Eigen::Vector3d(0, 0, -kGravity_m_s2), ContactLaw::kUnilateral);
  VisualFrame frame(stack, fem::FemOptions{}, fem::CalcGravityForce(stack, options.gravity_m_s2),
                    MakeSphereTool(), options);
  const fem::State body = RunWithTheToolAway(&frame, stack, 240);  // 4 s
  const BodyBodyContacts objects(stack, 0.001);
  Eigen::Vector3d on_upper_N = Eigen::Vector3d::Zero();
  int rows = 0;
  for (size_t i = 0; i < frame.contacts().size(); ++i) {
    const Contact& c = frame.contacts()[i];
    if (KindOf(c) != ContactKind::kBodyBody) continue;
    ++rows;
    const double lambda_N = frame.impulses()[static_cast<Eigen::Index>(i)];
    // +λn on the node's object, −λn on the face's.
    on_upper_N += (objects.object_of_node(c.nodes[0]) == 1 ? 1.0 : -1.0) * lambda_N * c.n_W;
  }
  const double weight_N = kDensity_kg_m3 * 0.02 * 0.02 * 0.01 * kGravity_m_s2;
  double lowest_upper_m = 1.0;
  for (int node = 75; node < stack.num_nodes(); ++node)
    lowest_upper_m = std::min(lowest_upper_m, body.x_m[3 * node + 2]);
  double top_under_m = 0.0;  // the lower block's top centre
  for (int node = 0; node < 75; ++node)
    if (std::abs(stack.rest_positions_m[3 * node]) < 1e-9 &&
        std::abs(stack.rest_positions_m[3 * node + 1]) < 1e-9 &&
        std::abs(stack.rest_positions_m[3 * node + 2] - 0.02) < 1e-9)
      top_under_m = body.x_m[3 * node + 2];
  std::printf(
      "%d body-body rows; force on the upper block %.6f %.6f %.6f N, weight %.6f N; its "
      "bottom %.4f mm above the lower top centre; speed %.1e m/s\n",
      rows, on_upper_N.x(), on_upper_N.y(), on_upper_N.z(), weight_N,
      1e3 * (lowest_upper_m - top_under_m), body.v_m_s.lpNorm<Eigen::Infinity>());
  EXPECT_LT(body.v_m_s.lpNorm<Eigen::Infinity>(), 1e-4) << "not at rest";
  EXPECT_NEAR(on_upper_N.z(), weight_N, 5e-3 * weight_N);
  EXPECT_LT(on_upper_N.head<2>().norm(), 1e-3 * weight_N);
  // Resting on the surface: neither hanging above it nor sunk in (β undoes an overlap).
  EXPECT_NEAR(lowest_upper_m, top_under_m, 1e-4);
}

INSTANTIATE_TEST_SUITE_P(LowerFixed, StackedBlock, testing::Bool(),
                         [](const testing::TestParamInfo<bool>& info) {
                           return info.param ? "Whole" : "AtItsBase";
                         });

// Friction between objects (the friction law's rows, three per contact, unchanged for a row
// between two of the body's objects): the upper block on the lower, fixed whole, under gravity
// tilted by θ with μ = 0.5 (friction angle 26.6°). At 20° it sticks; at 40° its centre of mass
// slides with a = g (sin θ − μ cos θ) = 2.549 m/s², less the drag of the mass-proportional
// Rayleigh damping α M v (α = 10 /s, MakeSoft): v̇ = a − α v, v(t) = (a/α)(1 − e^(−α t)).
Eigen::Vector3d SlideOnTheLowerBlock(double tilt_rad, double duration_s,
                                     Eigen::Vector3d* com_velocity_m_s) {
  const fem::Model stack = MakeStack(0.0, /*lower_fixed_whole=*/true);
  VisualFrameOptions options = MakeStackOptions(
      1.0 / 500.0, kGravity_m_s2 * Eigen::Vector3d(std::sin(tilt_rad), 0.0, -std::cos(tilt_rad)),
      ContactLaw::kFriction);
  options.response.solve.friction_coefficient = 0.5;
  VisualFrame frame(stack, fem::FemOptions{}, fem::CalcGravityForce(stack, options.gravity_m_s2),
                    MakeSphereTool(), options);
  const fem::State body =
      RunWithTheToolAway(&frame, stack, static_cast<int>(std::lround(duration_s / options.dt_s)));
  // The upper block's centre of mass (its nodes come after the lower's 75), moved and moving.
  Eigen::Vector3d moved_m = Eigen::Vector3d::Zero();
  com_velocity_m_s->setZero();
  double mass_kg = 0.0;
  for (int node = 75; node < stack.num_nodes(); ++node) {
    const double m = stack.node_mass_kg[node];
    moved_m += m * (body.x_m.segment<3>(3 * node) - stack.rest_positions_m.segment<3>(3 * node));
    *com_velocity_m_s += m * body.v_m_s.segment<3>(3 * node);
    mass_kg += m;
  }
  *com_velocity_m_s /= mass_kg;
  return moved_m / mass_kg;
}

TEST(BodyBodyContact, FrictionHoldsBelowTheFrictionAngleAndSlidesAbove) {
  Eigen::Vector3d v_stick, v_slide;
  const Eigen::Vector3d stick = SlideOnTheLowerBlock(20.0 * M_PI / 180.0, 0.2, &v_stick);
  const double steep_rad = 40.0 * M_PI / 180.0, t_s = 0.06;
  const Eigen::Vector3d slide = SlideOnTheLowerBlock(steep_rad, t_s, &v_slide);
  const double a_m_s2 = kGravity_m_s2 * (std::sin(steep_rad) - 0.5 * std::cos(steep_rad));
  const double alpha_1_s = MakeSoft(1.0).rayleigh_alpha_1_s;
  const double expected_m_s = a_m_s2 / alpha_1_s * (1.0 - std::exp(-alpha_1_s * t_s));
  std::printf(
      "upper block, mu 0.5: at 20 deg moved %.2e m along x, speed %.2e m/s; at 40 deg after "
      "%.2f s moving %.4f m/s along x ((a/alpha)(1 - exp(-alpha t)) = %.4f m/s; a t = %.4f), "
      "moved %.5f m\n",
      stick.x(), v_stick.x(), t_s, v_slide.x(), expected_m_s, a_m_s2 * t_s, slide.x());
  EXPECT_LT(std::abs(v_stick.x()), 1e-4);  // sticks: the elastic shear settles
  EXPECT_LT(std::abs(stick.x()), 1e-4);
  EXPECT_NEAR(v_slide.x(), expected_m_s, 0.02 * expected_m_s);
}

}  // namespace
}  // namespace hapsim::contact
