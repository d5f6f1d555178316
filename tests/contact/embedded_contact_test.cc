// Contacts on a collision surface embedded in the tets (contact/collision_detection.h,
// fem/surface_embedding.h), against the same contacts found on the tets' own boundary where the
// two surfaces coincide (a second computation: the boundary's nodes are the contact's nodes
// directly there):
//  - the boundary itself given as an embedded surface: the same contacts, the same Jacobian;
//  - the boundary with every face split in four (midpoint vertices, each carried by its tet): a
//    sphere touching a face's centre gives the face's own contact row, H = B N;
//  - a whole run of a scene whose `collision` surface is its boundary written as an OBJ file:
//    the device force of the run without it, in the default (hybrid), linear and penalty modes.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "config/body_builder.h"
#include "config/scene.h"
#include "contact/collision_detection.h"
#include "contact/contact_jacobian.h"
#include "fem/lattice_mesher.h"
#include "fem/model.h"
#include "fem/surface_embedding.h"
#include "tests/config/scene_test_support.h"
#include "tests/device/simulate_scene.h"

namespace hapsim::contact {
namespace {

using Eigen::Isometry3d;
using Eigen::Vector3d;

fem::Model MakeBlock(bool quadratic = false) {  // 6 × 6 × 3 cm, 1 cm cells, top z = 0.03
  const fem::TetMesh mesh =
      fem::MakeBoxTetMesh(Vector3d(-0.03, -0.03, 0.0), Vector3d(0.03, 0.03, 0.03), {6, 6, 3});
  return fem::MakeModel(quadratic ? fem::MakeQuadraticMesh(mesh) : mesh, fem::Material{}, {});
}

// The body with `vertices_m`, `triangles` embedded in its tets as its collision surface.
fem::Model WithCollisionSurface(fem::Model body, const Matrix3Xd& vertices_m,
                                const Matrix3Xi& triangles) {
  body.collision_surface = fem::EmbedSurface(body.mesh, vertices_m, triangles, 1e-9);
  return body;
}

// The boundary's own vertices (one per boundary node) and faces over them.
std::pair<Matrix3Xd, Matrix3Xi> BoundaryAsSurface(const fem::Model& body) {
  const fem::EmbeddedSurface own = fem::MakeNodeSurface(body.surface_triangles);
  Matrix3Xd vertices_m(3, own.num_points());
  for (int p = 0; p < own.num_points(); ++p)
    vertices_m.col(p) = body.mesh.rest_positions_m.col(own.nodes(0, p));
  return {vertices_m, own.triangles};
}

Eigen::MatrixXd DenseBodyRows(const std::vector<Contact>& contacts, const fem::Model& body) {
  return Eigen::MatrixXd(
      CalcContactJacobian(contacts, Vector3d::Zero(), 3, body.num_dofs(), body.dof_is_fixed).J_u);
}

TEST(EmbeddedContactTest, TheBoundaryEmbeddedGivesTheBoundarysContactsAndRows) {
  const fem::Model own = MakeBlock();
  const auto [vertices_m, triangles] = BoundaryAsSurface(own);
  const fem::Model embedded = WithCollisionSurface(own, vertices_m, triangles);
  // A tilted box pressed 1.5 mm into the top, over a displaced body: node, feature (corner) and
  // edge contacts.
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m = Vector3d(0.012, 0.008, 0.01);
  Isometry3d X_WT = Isometry3d::Identity();
  X_WT.linear() = Eigen::AngleAxisd(0.3, Vector3d(1.0, 0.4, 0.0).normalized()).toRotationMatrix();
  X_WT.translation() = Vector3d(0.002, -0.001, 0.0);
  double lowest_m = 1.0;  // of the corners; then lowered to 1.5 mm below the top
  for (int c = 0; c < 8; ++c) {
    const Vector3d corner((c & 1 ? 1 : -1) * 0.012, (c & 2 ? 1 : -1) * 0.008,
                          (c & 4 ? 1 : -1) * 0.01);
    lowest_m = std::min(lowest_m, (X_WT * corner).z());
  }
  X_WT.translation().z() = 0.03 - 0.0015 - lowest_m;
  Eigen::VectorXd x_m = own.rest_positions_m;
  for (int n = 0; n < own.num_nodes(); ++n)
    x_m.segment<3>(3 * n) += 1e-4 * Vector3d(std::sin(7.0 * n), std::cos(3.0 * n), std::sin(n));

  DetectionOptions options;
  std::vector<Contact> from_own, from_embedded;
  CollisionDetector(own, box, options).Detect(x_m, X_WT, x_m, X_WT, &from_own);
  CollisionDetector detector(embedded, box, options);
  detector.Detect(x_m, X_WT, x_m, X_WT, &from_embedded);
  EXPECT_GT(detector.statistics().num_node_contacts, 0);
  EXPECT_GT(detector.statistics().num_feature_contacts, 0);
  ASSERT_EQ(from_embedded.size(), from_own.size());
  ASSERT_GT(from_own.size(), 5u);
  for (size_t i = 0; i < from_own.size(); ++i) {
    EXPECT_TRUE(from_embedded[i].embedded);
    EXPECT_FALSE(from_own[i].embedded);
    EXPECT_LT((from_embedded[i].p_body_W_m - from_own[i].p_body_W_m).norm(), 1e-15);
    EXPECT_LT((from_embedded[i].n_W - from_own[i].n_W).norm(), 1e-15);
    EXPECT_NEAR(from_embedded[i].gap_m, from_own[i].gap_m, 1e-15);
  }
  // Each surface point is a node with weight 1 to round-off on its tet's other nodes.
  EXPECT_LT(
      (DenseBodyRows(from_embedded, embedded) - DenseBodyRows(from_own, own)).cwiseAbs().maxCoeff(),
      1e-12);
}

// With quadratic tets the boundary's faces are drawn as their four sub-triangles and a contact on
// one is weighed by the face's six shape functions (contact/quadratic_surface.h); the embedded
// point's weights are its tet's ten (fem/surface_embedding.h), which on a face are the same six.
class FaceSplitInFour : public testing::TestWithParam<bool> {};

TEST_P(FaceSplitInFour, CarriesTheFacesOwnRow) {
  const bool quadratic = GetParam();
  const fem::Model own = MakeBlock(quadratic);
  // Every boundary face split at its edges' midpoints into four (shared midpoints).
  const auto [vertices_m, triangles] = BoundaryAsSurface(own);
  std::vector<Vector3d> points(vertices_m.cols());
  for (Eigen::Index p = 0; p < vertices_m.cols(); ++p) points[p] = vertices_m.col(p);
  std::map<std::pair<int, int>, int> midpoint;
  const auto midpoint_of = [&](int a, int b) {
    const std::pair<int, int> key(std::min(a, b), std::max(a, b));
    const auto found = midpoint.find(key);
    if (found != midpoint.end()) return found->second;
    points.push_back(0.5 * (points[a] + points[b]));
    return midpoint[key] = static_cast<int>(points.size()) - 1;
  };
  Matrix3Xi fine(3, 4 * triangles.cols());
  for (Eigen::Index f = 0; f < triangles.cols(); ++f) {
    const int a = triangles(0, f), b = triangles(1, f), c = triangles(2, f);
    const int ab = midpoint_of(a, b), bc = midpoint_of(b, c), ca = midpoint_of(c, a);
    fine.col(4 * f) << a, ab, ca;
    fine.col(4 * f + 1) << ab, b, bc;
    fine.col(4 * f + 2) << ca, bc, c;
    fine.col(4 * f + 3) << ab, bc, ca;
  }
  Matrix3Xd fine_vertices_m(3, static_cast<Eigen::Index>(points.size()));
  for (size_t p = 0; p < points.size(); ++p) fine_vertices_m.col(p) = points[p];
  const fem::Model embedded = WithCollisionSurface(own, fine_vertices_m, fine);

  // A small sphere (0.5 mm: its cap, 0.32 mm across, reaches no vertex, even of the quadratic
  // block's faces split in four twice, 0.59 mm away) just touching the centroid of a top face.
  int top_face = -1;
  for (Eigen::Index f = 0; f < own.surface_triangles.cols() && top_face < 0; ++f) {
    bool on_top = true;
    for (int k = 0; k < 3; ++k)
      on_top = on_top && own.mesh.rest_positions_m(2, own.surface_triangles(k, f)) > 0.03 - 1e-12;
    if (on_top) top_face = static_cast<int>(f);
  }
  ASSERT_GE(top_face, 0);
  Vector3d centroid_m = Vector3d::Zero();
  for (int k = 0; k < 3; ++k)
    centroid_m += own.mesh.rest_positions_m.col(own.surface_triangles(k, top_face)) / 3.0;
  ToolShape sphere;
  sphere.kind = ToolShape::Kind::kSphere;
  sphere.radius_m = 0.0005;
  Isometry3d X_WT = Isometry3d::Identity();
  X_WT.translation() = centroid_m + Vector3d(0.0, 0.0, 0.0005 - 1e-4);  // 0.1 mm in
  DetectionOptions options;
  options.margin_m = 0.0;
  std::vector<Contact> from_own, from_embedded;
  const Eigen::VectorXd& x_m = own.rest_positions_m;
  CollisionDetector(own, sphere, options).Detect(x_m, X_WT, x_m, X_WT, &from_own);
  CollisionDetector(embedded, sphere, options).Detect(x_m, X_WT, x_m, X_WT, &from_embedded);
  ASSERT_EQ(from_own.size(), 1u);
  ASSERT_EQ(from_embedded.size(), 1u);
  EXPECT_LT((from_embedded[0].p_body_W_m - centroid_m).norm(), 1e-12);
  EXPECT_NEAR(from_embedded[0].gap_m, -1e-4, 1e-12);
  EXPECT_NEAR(from_own[0].gap_m, -1e-4, 1e-12);
  if (!quadratic) {
    EXPECT_LT((DenseBodyRows(from_embedded, embedded) - DenseBodyRows(from_own, own))
                  .cwiseAbs()
                  .maxCoeff(),
              1e-12);
    return;
  }
  // Quadratic: the embedded triangle is flat between its three points, each carried by the
  // quadratic field, so its row is Σ_k w_k N(ξ_k), not the face's N at the point (they differ by
  // O(h²) of the split). Checked on a quadratic displacement u of the nodes, which the points
  // follow exactly: the row times u is n · Σ_k w_k u(q_k), u evaluated at the triangle's vertices
  // q_k, w_k the point's barycentric coordinates in it.
  const Contact& contact = from_embedded[0];
  int num_nodes = 0;
  while (num_nodes < kMaxContactNodes && contact.nodes[num_nodes] >= 0) ++num_nodes;
  EXPECT_GT(num_nodes, 6) << "the row reaches past the face's own nodes";
  const auto u_m = [](const Vector3d& X_m) {
    const Vector3d X = X_m / 0.03;
    return Vector3d(0.002 * (X.x() * X.x() - X.y() * X.z()), 0.001 * X.x() * X.y(),
                    0.003 * (X.y() * X.y() + 0.5 * X.x() * X.z()));
  };
  Eigen::VectorXd u_nodes_m(own.num_dofs());
  for (int n = 0; n < own.num_nodes(); ++n)
    u_nodes_m.segment<3>(3 * n) = u_m(own.mesh.rest_positions_m.col(n));
  Eigen::Matrix<double, 3, 2> edges;
  const Vector3d q0 = fine_vertices_m.col(contact.surface_points[0]);
  for (int k = 1; k < 3; ++k)
    edges.col(k - 1) = fine_vertices_m.col(contact.surface_points[k]) - q0;
  const Eigen::Vector2d w12 = edges.colPivHouseholderQr().solve(contact.p_body_W_m - q0);
  const double w[3] = {1.0 - w12.sum(), w12.x(), w12.y()};
  Vector3d expected_m = Vector3d::Zero();
  for (int k = 0; k < 3; ++k)
    expected_m += w[k] * u_m(fine_vertices_m.col(contact.surface_points[k]));
  const Eigen::MatrixXd rows = DenseBodyRows(from_embedded, embedded);
  EXPECT_NEAR(rows.row(0).dot(u_nodes_m), contact.n_W.dot(expected_m), 1e-15);
  EXPECT_GT(std::abs(contact.n_W.dot(expected_m)), 1e-5);  // the field moves the point
}

INSTANTIATE_TEST_SUITE_P(EmbeddedContactTest, FaceSplitInFour, testing::Bool(),
                         [](const testing::TestParamInfo<bool>& info) {
                           return info.param ? "QuadraticTets" : "LinearTets";
                         });

// A 6 × 6 × 3 cm block pressed by a sphere; `collision` added by the caller.
constexpr const char* kPressScene = R"(name: press
time: {dt_s: 0.02, num_steps: 40}
body:
  mesh: {box: {min_m: [-0.03, -0.03, 0.0], max_m: [0.03, 0.03, 0.03], cells: [6, 6, 3]}}
  material: {youngs_modulus_Pa: 50000, poisson_ratio: 0.4, density_kg_m3: 1000,
             rayleigh_beta_s: 0.01}
  solver: {type: cholmod}
  fixed: {min_m: [-0.04, -0.04, -0.001], max_m: [0.04, 0.04, 0.001]}
tool:
  shape: {sphere: {radius_m: 0.012}}
  mass_kg: 0.05
  position_m: [0.002, 0.001, 0.043]
coupling: {k_lin_N_m: 1000, b_lin_N_s_m: 2, k_ang_N_m_rad: 1, b_ang_N_m_s_rad: 0.005}
device:
  trajectory:
    - {t_s: 0.0, position_m: [0.002, 0.001, 0.043]}
    - {t_s: 0.5, position_m: [0.002, 0.001, 0.038]}
    - {t_s: 0.8, position_m: [0.006, 0.001, 0.038]}
)";

// Writes the press scene's boundary into `folder` as the OBJ file `name`, its coordinates times
// `scale` (a file in other units); returns its number of vertices.
Eigen::Index WritePressBoundary(const config::test::TempFolder& folder, const std::string& name,
                                double scale) {
  const config::Scene plain = config::ParseScene(kPressScene, "press.yaml", folder.path());
  const auto [vertices_m, triangles] = BoundaryAsSurface(config::MakeSceneBody(plain)->model);
  std::ofstream((std::filesystem::path(folder.path()) / name).string())
      << config::test::ObjText(scale * vertices_m, triangles);
  return vertices_m.cols();
}

TEST(EmbeddedContactTest, ARunWithTheBoundaryAsItsCollisionSurfaceFeelsTheSame) {
  const config::test::TempFolder folder("embedded_press");
  const config::Scene plain = config::ParseScene(kPressScene, "press.yaml", folder.path());
  const config::Body plain_body = *config::MakeSceneBody(plain);
  const Eigen::Index num_vertices = WritePressBoundary(folder, "boundary.obj", 1.0);
  const std::string with_surface = config::test::Replace(
      kPressScene, "  solver:", "  collision: {file: boundary.obj}\n  solver:");
  const config::Scene embedded = config::ParseScene(with_surface, "press.yaml", folder.path());
  const config::Body embedded_body = *config::MakeSceneBody(embedded);
  ASSERT_FALSE(embedded_body.model.collision_surface.empty());
  EXPECT_EQ(embedded_body.model.collision_surface.num_points(), num_vertices);

  // The default, the paper's model, and penalty (contacts searched at 1 kHz on the frame's
  // surface, the tree refitted once a frame).
  using device::HapticMode;
  for (const HapticMode mode : {HapticMode::kHybrid, HapticMode::kLinear, HapticMode::kPenalty}) {
    const std::vector<device::HapticSample> a = device::SimulateScene(plain, mode, &plain_body);
    const std::vector<device::HapticSample> b =
        device::SimulateScene(embedded, mode, &embedded_body);
    ASSERT_EQ(a.size(), b.size());
    double peak_N = 0.0, difference_N = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
      peak_N = std::max(peak_N, a[i].device_force_W_N.norm());
      difference_N = std::max(difference_N, (a[i].device_force_W_N - b[i].device_force_W_N).norm());
    }
    EXPECT_GT(peak_N, 0.5) << "the sphere must press";
    EXPECT_LT(difference_N, 1e-9 * peak_N) << "mode " << static_cast<int>(mode);
  }
}

// A collision surface written in millimetres and given without `units: mm` lies metres away from
// the tets: refused at its key, naming the file; with the units it loads.
TEST(EmbeddedContactTest, ASurfaceInOtherUnitsIsRefusedAtItsKeyUntilTheyAreGiven) {
  const config::test::TempFolder folder("embedded_units");
  const Eigen::Index num_vertices = WritePressBoundary(folder, "boundary_mm.obj", 1000.0);
  const std::string without_units = config::test::Replace(
      kPressScene, "  solver:", "  collision: {file: boundary_mm.obj}\n  solver:");
  const config::Scene scene = config::ParseScene(without_units, "press.yaml", folder.path());
  try {
    config::MakeSceneBody(scene);
    FAIL() << "a surface 1000 times too large was embedded";
  } catch (const InputError& error) {
    EXPECT_EQ(error.file(), "press.yaml");
    EXPECT_EQ(error.line(), 7);
    EXPECT_EQ(error.key(), "body.collision") << error.what();
    EXPECT_NE(std::string(error.what()).find("boundary_mm.obj"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("outside every tet"), std::string::npos);
  }
  const std::string with_units = config::test::Replace(
      kPressScene, "  solver:", "  collision: {file: boundary_mm.obj, units: mm}\n  solver:");
  const config::Body body =
      *config::MakeSceneBody(config::ParseScene(with_units, "press.yaml", folder.path()));
  EXPECT_EQ(body.model.collision_surface.num_points(), num_vertices);
}

}  // namespace
}  // namespace hapsim::contact
