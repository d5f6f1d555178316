// Collision detection (contact/collision_detection.h) against brute force over every surface
// node with closed-form signed distances, and against hand-computed contacts.

#include "contact/collision_detection.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <string>

#include "contact/contact_jacobian.h"
#include "fem/lattice_mesher.h"
#include "fem/model.h"

namespace hapsim::contact {
namespace {

using Eigen::Isometry3d;
using Eigen::Vector3d;

constexpr double kExactTolerance_m = 1e-12;  // round-off on O(10 cm) coordinates

fem::Model MakeBlock(const Vector3d& max_m, const Eigen::Vector3i& cells) {
  return fem::MakeModel(fem::MakeBoxTetMesh(Vector3d::Zero(), max_m, cells), fem::Material{}, {});
}

// The 10 × 10 × 5 cm block with 1 cm cells; top face z = 0.05.
fem::Model MakeReferenceBlock() { return MakeBlock(Vector3d(0.1, 0.1, 0.05), {10, 10, 5}); }

std::set<int> SurfaceNodes(const fem::Model& body) {
  const Matrix3Xi& faces = body.surface_triangles;
  return std::set<int>(faces.data(), faces.data() + faces.size());
}

Isometry3d Pose(const Eigen::Matrix3d& R, const Vector3d& t) {
  Isometry3d X = Isometry3d::Identity();
  X.linear() = R;
  X.translation() = t;
  return X;
}

// Closed-form signed distances in the tool frame (independent of contact/tool_distance.cc).
double ToolSdf(const ToolShape& tool, const Vector3d& p) {
  switch (tool.kind) {
    case ToolShape::Kind::kSphere:
      return p.norm() - tool.radius_m;
    case ToolShape::Kind::kCapsule: {
      const double z = std::max(std::abs(p.z()) - 0.5 * tool.length_m, 0.0);
      return Vector3d(p.x(), p.y(), z).norm() - tool.radius_m;
    }
    case ToolShape::Kind::kCylinder: {
      const Eigen::Vector2d d(std::hypot(p.x(), p.y()) - tool.radius_m,
                              std::abs(p.z()) - 0.5 * tool.length_m);
      return std::min(d.maxCoeff(), 0.0) + d.cwiseMax(0.0).norm();
    }
    case ToolShape::Kind::kBox: {
      const Vector3d q = p.cwiseAbs() - tool.half_extents_m;
      return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
    }
    case ToolShape::Kind::kMesh:
      break;
  }
  throw std::logic_error("no closed form for a mesh");
}

// Radius of the smallest sphere about the tool origin holding the tool.
double BoundingRadius(const ToolShape& tool) {
  switch (tool.kind) {
    case ToolShape::Kind::kSphere:
      return tool.radius_m;
    case ToolShape::Kind::kCapsule:
      return tool.radius_m + 0.5 * tool.length_m;
    case ToolShape::Kind::kCylinder:
      return std::hypot(tool.radius_m, 0.5 * tool.length_m);
    case ToolShape::Kind::kBox:
      return tool.half_extents_m.norm();
    case ToolShape::Kind::kMesh:
      break;
  }
  throw std::logic_error("not a primitive");
}

// node → gap of the node-versus-tool contacts (weights {1, 0, 0}).
std::map<int, double> NodeContactGaps(const std::vector<Contact>& contacts) {
  std::map<int, double> gaps;
  for (const Contact& c : contacts)
    if (c.nodes[1] < 0) {
      EXPECT_TRUE(gaps.emplace(c.nodes[0], c.gap_m).second) << "node twice";
    }
  return gaps;
}

std::map<int, double> BruteForceGaps(const fem::Model& body, const Eigen::VectorXd& x_m,
                                     const ToolShape& tool, const Isometry3d& X_WT,
                                     double threshold_m) {
  std::map<int, double> gaps;
  for (int n : SurfaceNodes(body)) {
    const double gap = ToolSdf(tool, X_WT.inverse() * Vector3d(x_m.segment<3>(3 * n)));
    if (gap <= threshold_m) gaps[n] = gap;
  }
  return gaps;
}

void ExpectSameGaps(const std::map<int, double>& actual, const std::map<int, double>& expected) {
  ASSERT_EQ(actual.size(), expected.size());
  for (const auto& [node, gap] : expected) {
    ASSERT_EQ(actual.count(node), 1u) << "missing node " << node;
    EXPECT_NEAR(actual.at(node), gap, kExactTolerance_m) << node;
  }
}

TEST(CollisionDetectionTest, SphereRestingOnBlockFindsExactlyTheNodesInside) {
  const fem::Model body = MakeReferenceBlock();
  ToolShape sphere;
  sphere.radius_m = 0.02;
  const Vector3d c(0.052, 0.047, 0.05 + 0.02 - 0.004);  // 4 mm penetration
  const Isometry3d X_WT = Pose(Eigen::Matrix3d::Identity(), c);
  DetectionOptions options;
  options.continuous = false;
  CollisionDetector detector(body, sphere, options);
  std::vector<Contact> contacts;
  const Eigen::VectorXd& x = body.rest_positions_m;
  detector.Detect(x, X_WT, x, X_WT, &contacts);

  int num_inside = 0;  // every node of the mesh, interior ones included
  for (int n = 0; n < body.num_nodes(); ++n)
    if ((x.segment<3>(3 * n) - c).norm() < sphere.radius_m) ++num_inside;
  EXPECT_GE(num_inside, 3);
  const auto is_node = [](const Contact& k) { return k.nodes[1] < 0; };
  EXPECT_EQ(std::count_if(contacts.begin(), contacts.end(),
                          [&](const Contact& k) { return is_node(k) && k.gap_m < 0.0; }),
            num_inside);
  ExpectSameGaps(NodeContactGaps(contacts),
                 BruteForceGaps(body, x, sphere, X_WT, options.margin_m));
  double deepest_face_gap_m = 1.0;
  for (const Contact& k : contacts) {
    if (!is_node(k)) {
      // The centre against the top (z = 0.05) faces: a point of the top plane, its gap the
      // distance to it less r, the normal along it; the face right under the centre is 4 mm deep.
      EXPECT_NEAR(k.p_body_W_m.z(), 0.05, 1e-15);
      const Vector3d to_centre = c - k.p_body_W_m;
      EXPECT_NEAR(k.gap_m, to_centre.norm() - sphere.radius_m, kExactTolerance_m);
      EXPECT_LT((k.n_W + to_centre.normalized()).norm(), 1e-12);
      EXPECT_NEAR(k.gap_m, (k.p_body_W_m - k.p_tool_W_m).dot(k.n_W), kExactTolerance_m);
      deepest_face_gap_m = std::min(deepest_face_gap_m, k.gap_m);
      continue;
    }
    const Vector3d p = x.segment<3>(3 * k.nodes[0]);
    const Vector3d n = (p - c).normalized();
    EXPECT_NEAR(k.gap_m, (p - c).norm() - sphere.radius_m, kExactTolerance_m);
    EXPECT_LT((k.n_W - n).norm(), 1e-12);
    EXPECT_LT((k.p_tool_W_m - (c + sphere.radius_m * n)).norm(), kExactTolerance_m);
    EXPECT_TRUE(k.p_body_W_m == p);
    EXPECT_NEAR(k.gap_m, (k.p_body_W_m - k.p_tool_W_m).dot(k.n_W), kExactTolerance_m);
  }
  EXPECT_NEAR(deepest_face_gap_m, -0.004, kExactTolerance_m);
  EXPECT_EQ(detector.statistics().num_contacts_after_merge, static_cast<int>(contacts.size()));
}

// A flat punch (a sharp-rimmed cylinder, radius 13 mm over 1 cm cells) pressed 2 mm into the top:
// its rim crosses faces between their nodes. By default the rim's points and segments press those
// faces (feature and edge contacts); with both stages off (a scene's contact.tool_features:
// false, node-to-surface contact) exactly the surface nodes within the margin of the tool are in
// contact, each at its closed-form signed distance, and nothing else.
TEST(CollisionDetectionTest, PunchWithoutToolFeaturesTouchesOnlyTheNodes) {
  const fem::Model body = MakeReferenceBlock();
  ToolShape punch;
  punch.kind = ToolShape::Kind::kCylinder;
  punch.radius_m = 0.013;
  punch.length_m = 0.02;
  const Isometry3d X_WT =
      Pose(Eigen::Matrix3d::Identity(), Vector3d(0.052, 0.047, 0.05 + 0.01 - 0.002));
  const Eigen::VectorXd& x = body.rest_positions_m;
  const auto is_node = [](const Contact& k) { return k.nodes[1] < 0; };
  for (const bool features : {true, false}) {
    DetectionOptions options;
    options.continuous = false;
    options.feature_contacts = features;
    options.edge_contacts = features;
    CollisionDetector detector(body, punch, options);
    std::vector<Contact> contacts;
    detector.Detect(x, X_WT, x, X_WT, &contacts);
    const auto num_nodes = std::count_if(contacts.begin(), contacts.end(), is_node);
    if (features) {
      EXPECT_GT(detector.statistics().num_feature_contacts, 0);
      EXPECT_GT(static_cast<long>(contacts.size()), num_nodes) << "no rim contact on a face";
    } else {
      EXPECT_EQ(detector.statistics().num_feature_contacts, 0);
      EXPECT_EQ(detector.statistics().num_edge_contacts, 0);
      EXPECT_EQ(static_cast<long>(contacts.size()), num_nodes);
      ExpectSameGaps(NodeContactGaps(contacts),
                     BruteForceGaps(body, x, punch, X_WT, options.margin_m));
    }
  }
}

// A sphere much smaller than the faces, 0.5 mm into the top between nodes (1 cm cells): no node
// is near it, so its centre against the face under it holds it, with gap −0.5 mm along the
// face normal. Without that contact the sphere would fall through the face.
TEST(CollisionDetectionTest, SmallSphereBetweenNodesIsHeldByTheFaceUnderIt) {
  const fem::Model body = MakeReferenceBlock();
  ToolShape sphere;
  sphere.radius_m = 0.001;
  const Vector3d c(0.0537, 0.0461, 0.05 + 0.001 - 0.0005);
  DetectionOptions options;
  options.continuous = false;
  CollisionDetector detector(body, sphere, options);
  std::vector<Contact> contacts;
  const Eigen::VectorXd& x = body.rest_positions_m;
  detector.Detect(x, Pose(Eigen::Matrix3d::Identity(), c), x, Pose(Eigen::Matrix3d::Identity(), c),
                  &contacts);
  // The face under it, and any neighbour whose nearest point (on their shared edge) is within
  // the margin; no node.
  ASSERT_GE(contacts.size(), 1u);
  for (const Contact& other : contacts) {
    EXPECT_GE(other.nodes[1], 0);
    EXPECT_NEAR(other.gap_m, (c - other.p_body_W_m).norm() - sphere.radius_m, kExactTolerance_m);
  }
  const Contact& k =
      *std::min_element(contacts.begin(), contacts.end(),
                        [](const Contact& p, const Contact& q) { return p.gap_m < q.gap_m; });
  EXPECT_GE(k.nodes[2], 0);  // on a face's three nodes
  EXPECT_NEAR(k.gap_m, -0.0005, kExactTolerance_m);
  EXPECT_LT((k.n_W - Vector3d(0, 0, -1)).norm(), 1e-12);
  EXPECT_LT((k.p_body_W_m - Vector3d(c.x(), c.y(), 0.05)).norm(), kExactTolerance_m);
  double weight_sum = 0.0;
  Vector3d weighted = Vector3d::Zero();
  for (int i = 0; i < 3; ++i) {
    weight_sum += k.weights[i];
    weighted += k.weights[i] * x.segment<3>(3 * k.nodes[i]);
  }
  EXPECT_NEAR(weight_sum, 1.0, 1e-12);
  EXPECT_LT((weighted - k.p_body_W_m).norm(), kExactTolerance_m);  // its barycentric weights
}

// After a large deformation the refitted BVH must still find every node: each tool kind, at a
// random orientation, against brute force over all surface nodes, with and without the sweep.
TEST(CollisionDetectionTest, DeformedBodyMatchesBruteForceForEveryPrimitive) {
  const fem::Model body = MakeBlock(Vector3d(0.1, 0.1, 0.05), {20, 20, 10});  // 5 mm cells
  int top_node = 0;  // the node at the top centre
  for (int n = 0; n < body.num_nodes(); ++n)
    if ((body.rest_positions_m.segment<3>(3 * n) - Vector3d(0.05, 0.05, 0.05)).norm() < 1e-12)
      top_node = n;
  std::mt19937 engine(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd x = body.rest_positions_m;
  for (int n = 0; n < body.num_nodes(); ++n) {
    const Vector3d X = body.rest_positions_m.segment<3>(3 * n);
    const double bump = 0.01 * std::sin(M_PI * X.x() / 0.1) * std::sin(M_PI * X.y() / 0.1);
    x.segment<3>(3 * n) += Vector3d(0.004 * X.z() / 0.05, 0.0, bump * X.z() / 0.05) +
                           5e-4 * Vector3d(u(engine), u(engine), u(engine));
  }
  std::vector<ToolShape> tools(4);
  tools[0].radius_m = 0.015;
  tools[1].kind = ToolShape::Kind::kCapsule;
  tools[1].radius_m = 0.006;
  tools[1].length_m = 0.03;
  tools[2].kind = ToolShape::Kind::kCylinder;
  tools[2].radius_m = 0.008;
  tools[2].length_m = 0.02;
  tools[3].kind = ToolShape::Kind::kBox;
  tools[3].half_extents_m = Vector3d(0.012, 0.008, 0.006);
  DetectionOptions options;
  options.margin_m = 2e-3;
  options.feature_merge_distance_m = 0.0;  // keep every node contact for the comparison
  for (const ToolShape& tool : tools) {
    for (int variant = 0; variant < 3; ++variant) {  // discrete; continuous, AABB and OBBRSS
      const bool continuous = variant > 0;
      options.continuous = continuous;
      const SurfaceBvhKind bvh = variant == 2 ? SurfaceBvhKind::kObbrss : SurfaceBvhKind::kAabb;
      SCOPED_TRACE("tool kind " + std::to_string(static_cast<int>(tool.kind)) + ", variant " +
                   std::to_string(variant));
      CollisionDetector detector(body, tool, options, bvh);
      std::vector<Contact> contacts;
      const Eigen::Matrix3d R =
          Eigen::AngleAxisd(2.0, Vector3d(u(engine), u(engine), 1.0).normalized()).matrix();
      const Isometry3d X_start = Pose(R, Vector3d(0.045, 0.052, 0.056));
      // A first frame at rest, so that the second one exercises the refit.
      detector.Detect(body.rest_positions_m, X_start, body.rest_positions_m, X_start, &contacts);
      const Eigen::Matrix3d dR = Eigen::AngleAxisd(0.05, Vector3d::UnitX()).matrix();
      const Isometry3d X_end = Pose(dR * R, X_start.translation() + Vector3d(0.0, 0.002, -0.004));
      Eigen::VectorXd x_end = x;
      x_end.segment<3>(3 * top_node) += Vector3d(0.0, 0.0, 0.003);  // the largest move, 3 mm
      detector.Detect(x, X_start, x_end, X_end, &contacts);
      // Tool translation + rotation angle × bounding radius + max node displacement.
      const double sweep_m =
          continuous ? std::hypot(0.002, 0.004) + 0.05 * BoundingRadius(tool) + 0.003 : 0.0;
      EXPECT_NEAR(detector.statistics().sweep_bound_m, sweep_m, 1e-12);
      const std::map<int, double> expected =
          BruteForceGaps(body, x, tool, X_start, options.margin_m + sweep_m);
      EXPECT_GE(expected.size(), 8u);
      ExpectSameGaps(NodeContactGaps(contacts), expected);
    }
  }
}

// A sphere that the free update carries 16 cm through a 1 cm slab in one frame: the end pose is
// collision-free, so only the swept search sees the slab.
TEST(CollisionDetectionTest, FastSphereDoesNotTunnelThroughThinSlab) {
  const fem::Model slab = MakeBlock(Vector3d(0.1, 0.1, 0.01), {10, 10, 2});
  ToolShape sphere;
  sphere.radius_m = 0.01;
  const Isometry3d X_start = Pose(Eigen::Matrix3d::Identity(), Vector3d(0.05, 0.05, 0.03));
  const Isometry3d X_end = Pose(Eigen::Matrix3d::Identity(), Vector3d(0.05, 0.05, -0.13));
  const Eigen::VectorXd& x = slab.rest_positions_m;
  DetectionOptions options;
  std::vector<Contact> contacts;

  options.continuous = false;
  CollisionDetector discrete(slab, sphere, options);
  discrete.Detect(x, X_start, x, X_end, &contacts);
  EXPECT_TRUE(contacts.empty());
  discrete.Detect(x, X_end, x, X_end, &contacts);  // nor at the end: the sphere tunnelled
  EXPECT_TRUE(contacts.empty());

  options.continuous = true;
  CollisionDetector swept(slab, sphere, options);
  swept.Detect(x, X_start, x, X_end, &contacts);
  EXPECT_NEAR(swept.statistics().sweep_bound_m, 0.16, 1e-15);
  ASSERT_FALSE(contacts.empty());
  const auto nearest =
      std::min_element(contacts.begin(), contacts.end(),
                       [](const Contact& a, const Contact& b) { return a.gap_m < b.gap_m; });
  EXPECT_NEAR(nearest->gap_m, 0.01, kExactTolerance_m);  // node (0.05, 0.05, 0.01) below
  EXPECT_LT((nearest->p_body_W_m - Vector3d(0.05, 0.05, 0.01)).norm(), kExactTolerance_m);
  EXPECT_LT((nearest->n_W - Vector3d(0.0, 0.0, -1.0)).norm(), 1e-12);
  int near_face = 0;
  for (const Contact& k : contacts)
    if (k.gap_m < 0.015) {  // every contact the solver would act on first is on the near face
      EXPECT_NEAR(k.p_body_W_m.z(), 0.01, kExactTolerance_m);
      EXPECT_LT(k.n_W.z(), 0.0);
      ++near_face;
    }
  EXPECT_GE(near_face, 5);
}

// A cube standing on a corner, pressed 2 mm into the top face away from any node.
TEST(CollisionDetectionTest, BoxCornerIntoFaceGivesBarycentricFeatureContact) {
  const fem::Model body = MakeReferenceBlock();
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m = Vector3d::Constant(0.01);
  const Eigen::Matrix3d R =
      Eigen::Quaterniond::FromTwoVectors(Vector3d::Ones(), Vector3d::UnitZ()).matrix();
  const Vector3d corner_W(0.0234, 0.0371, 0.05 - 0.002);  // corner (−,−,−) ends up lowest
  const Isometry3d X_WT = Pose(R, corner_W + Vector3d(0.0, 0.0, std::sqrt(3.0) * 0.01));
  ASSERT_LT((X_WT * Vector3d::Constant(-0.01) - corner_W).norm(), 1e-15);
  CollisionDetector detector(body, box, DetectionOptions{});
  std::vector<Contact> contacts;
  detector.Detect(body.rest_positions_m, X_WT, body.rest_positions_m, X_WT, &contacts);
  std::vector<Contact> features;  // face contacts: three nodes
  for (const Contact& k : contacts)
    if (k.nodes[2] >= 0) features.push_back(k);
  ASSERT_EQ(features.size(), 1u);
  // The three edges from the buried corner cross the top face 2.8 mm out; where they pass under
  // a body edge, that edge's point is inside the cube (an edge contact is a real overlap).
  const DetectionStatistics& statistics = detector.statistics();
  EXPECT_EQ(statistics.num_edge_contacts, statistics.num_contacts_before_merge -
                                              statistics.num_node_contacts -
                                              statistics.num_feature_contacts);
  for (const Contact& k : contacts)
    if (k.nodes[1] >= 0 && k.nodes[2] < 0 && k.gap_m < 0.0) {
      EXPECT_LT(ToolSdf(box, X_WT.inverse() * k.p_body_W_m), 0.0);
      EXPECT_LT(k.p_tool_W_m.z(), 0.05);
    }
  const Contact& k = features.front();
  EXPECT_LT((k.p_tool_W_m - corner_W).norm(), kExactTolerance_m);
  EXPECT_LT((k.p_body_W_m - Vector3d(0.0234, 0.0371, 0.05)).norm(), kExactTolerance_m);
  EXPECT_LT((k.n_W - Vector3d(0.0, 0.0, -1.0)).norm(), 1e-12);
  EXPECT_NEAR(k.gap_m, -0.002, kExactTolerance_m);
  EXPECT_NEAR(k.weights[0] + k.weights[1] + k.weights[2], 1.0, 1e-15);
  Vector3d combination = Vector3d::Zero();
  for (int i = 0; i < 3; ++i) {
    EXPECT_GE(k.weights[i], 0.0);
    const Vector3d node = body.rest_positions_m.segment<3>(3 * k.nodes[i]);
    EXPECT_NEAR(node.z(), 0.05, 1e-15);  // a top-face triangle
    combination += k.weights[i] * node;
  }
  EXPECT_LT((combination - k.p_body_W_m).norm(), kExactTolerance_m);
}

// A box whose corner sits 0.07 mm (< feature_merge_distance) from a top node that is itself
// inside the box: the node contact and the corner contact are the same constraint.
void CheckDuplicateMerged(double node_lift_m, bool node_contact_survives) {
  const fem::Model body = MakeReferenceBlock();
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m = Vector3d(0.0123, 0.0087, 0.006);
  const Vector3d node_W(0.03, 0.04, 0.05);
  int node = -1;
  for (int n = 0; n < body.num_nodes(); ++n)
    if ((body.rest_positions_m.segment<3>(3 * n) - node_W).norm() < 1e-12) node = n;
  ASSERT_GE(node, 0);
  const Vector3d corner_W = node_W + Vector3d(5e-5, 5e-5, -2e-5);  // corner (+,+,−)
  const Isometry3d X_WT = Pose(Eigen::Matrix3d::Identity(),
                               corner_W - box.half_extents_m.cwiseProduct(Vector3d(1, 1, -1)));
  Eigen::VectorXd x = body.rest_positions_m;
  x[3 * node + 2] += node_lift_m;
  // The box's bottom edges, 2e-5 below the top face, cross body edges within the merge radius of
  // other top nodes: their edge contacts merge too. This test is about the node/corner pair.
  DetectionOptions options;
  options.edge_contacts = false;
  CollisionDetector detector(body, box, options);
  std::vector<Contact> contacts;
  detector.Detect(x, X_WT, x, X_WT, &contacts);
  const DetectionStatistics& statistics = detector.statistics();
  EXPECT_EQ(statistics.num_contacts_before_merge - statistics.num_contacts_after_merge, 1);
  int node_contacts = 0, corner_contacts = 0;
  for (const Contact& k : contacts) {
    if ((k.p_body_W_m - Vector3d(x.segment<3>(3 * node))).norm() > 1e-4) continue;
    EXPECT_LT((k.n_W - Vector3d(0.0, 0.0, -1.0)).norm(), 1e-3);
    (k.nodes[1] < 0 ? node_contacts : corner_contacts)++;
  }
  EXPECT_EQ(node_contacts, node_contact_survives ? 1 : 0);
  EXPECT_EQ(corner_contacts, node_contact_survives ? 0 : 1);
}

TEST(CollisionDetectionTest, DuplicateKeepsTheDeeperNodeContact) {
  CheckDuplicateMerged(5e-6, /*node_contact_survives=*/true);  // node 2.5e-5 deep, corner 2e-5
}

TEST(CollisionDetectionTest, DuplicateKeepsTheDeeperFeatureContact) {
  CheckDuplicateMerged(-5e-6, /*node_contact_survives=*/false);  // node 1.5e-5 deep, corner 2e-5
}

// A box given as a 12-triangle mesh yields the same contacts as the box primitive.
TEST(CollisionDetectionTest, MeshToolMatchesPrimitive) {
  const fem::Model body = MakeReferenceBlock();
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m = Vector3d(0.012, 0.008, 0.006);
  ToolShape mesh;
  mesh.kind = ToolShape::Kind::kMesh;
  mesh.mesh.vertices_m.resize(3, 8);
  for (int c = 0; c < 8; ++c)
    mesh.mesh.vertices_m.col(c) = Vector3d((c & 1) ? 1 : -1, (c & 2) ? 1 : -1, (c & 4) ? 1 : -1)
                                      .cwiseProduct(box.half_extents_m);
  mesh.mesh.triangles.resize(3, 12);
  int f = 0;  // each face: the 4 corners with one bit fixed, split along the 0–3 diagonal
  for (int bit : {1, 2, 4})
    for (int value : {0, bit}) {
      std::vector<int> q;
      for (int c = 0; c < 8; ++c)
        if ((c & bit) == value) q.push_back(c);
      for (const Eigen::Vector3i& t :
           {Eigen::Vector3i(q[0], q[1], q[3]), Eigen::Vector3i(q[0], q[3], q[2])}) {
        const auto v = [&](int k) { return Vector3d(mesh.mesh.vertices_m.col(t[k])); };
        const bool outward = (v(1) - v(0)).cross(v(2) - v(0)).dot(v(0)) > 0.0;
        mesh.mesh.triangles.col(f++) = outward ? t : Eigen::Vector3i(t[0], t[2], t[1]);
      }
    }
  const Isometry3d X_WT =
      Pose(Eigen::AngleAxisd(0.7, Vector3d(1.0, -2.0, 0.5).normalized()).matrix(),
           Vector3d(0.047, 0.053, 0.054));
  DetectionOptions options;
  options.margin_m = 3e-3;
  options.max_feature_penetration_m = 0.05;  // this pose buries a corner deeper than the default
  std::vector<Contact> from_box, from_mesh;
  CollisionDetector(body, box, options)
      .Detect(body.rest_positions_m, X_WT, body.rest_positions_m, X_WT, &from_box);
  CollisionDetector(body, mesh, options)
      .Detect(body.rest_positions_m, X_WT, body.rest_positions_m, X_WT, &from_mesh);
  ASSERT_GT(from_box.size(), 5u);
  ASSERT_EQ(from_mesh.size(), from_box.size());
  for (size_t i = 0; i < from_box.size(); ++i) {
    EXPECT_EQ(from_mesh[i].nodes, from_box[i].nodes);
    EXPECT_NEAR(from_mesh[i].gap_m, from_box[i].gap_m, kExactTolerance_m);
    EXPECT_LT((from_mesh[i].p_tool_W_m - from_box[i].p_tool_W_m).norm(), kExactTolerance_m);
    EXPECT_LT((from_mesh[i].n_W - from_box[i].n_W).norm(), 1e-9);
  }
}

// Edge contacts of a detection: two nodes, the third slot unused.
std::vector<Contact> EdgeContacts(const std::vector<Contact>& contacts) {
  std::vector<Contact> edges;
  for (const Contact& k : contacts)
    if (k.nodes[1] >= 0 && k.nodes[2] < 0) edges.push_back(k);
  return edges;
}

// A knife edge across the block's top-front edge (along x at y = 0, z = 0.05; its faces' outward
// normals +z and −y). The box's edge runs along u = (0, 1, 1)/√2 in the plane x = x0, between box
// faces with outward normals (x ± w)/√2 for w = (0, 1, −1)/√2, so the box lies above and in front
// of the block and only its edge, at depth δ along w, dips into the block's corner. The block's
// edge is inside the box for |x − x0| ≤ δ only: its nodes (x = 0.03, 0.04) stay 2.6 mm or more
// outside the box, and the box's corners 13 mm or more from the block.
struct KnifeEdge {
  ToolShape box;
  Isometry3d X_WT;
  Vector3d u, w;         // edge direction; common normal of the two edges, into the block
  Vector3d p_block_W_m;  // the block edge's point closest to the knife edge
  Vector3d p_edge_W_m;   // the knife edge's point closest to the block edge
};

KnifeEdge MakeKnifeEdge(double depth_m) {
  KnifeEdge knife;
  knife.box.kind = ToolShape::Kind::kBox;
  knife.box.half_extents_m = Vector3d(0.02, 0.01, 0.01);
  knife.u = Vector3d(0.0, 1.0, 1.0) / std::sqrt(2.0);
  knife.w = Vector3d(0.0, 1.0, -1.0) / std::sqrt(2.0);
  Eigen::Matrix3d R;  // columns: T's x along the edge, T's y and z the normals of its two faces
  R.col(0) = knife.u;
  R.col(1) = (Vector3d::UnitX() + knife.w) / std::sqrt(2.0);
  R.col(2) = (knife.w - Vector3d::UnitX()) / std::sqrt(2.0);
  knife.p_block_W_m = Vector3d(0.0347, 0.0, 0.05);
  knife.p_edge_W_m = knife.p_block_W_m + depth_m * knife.w;
  // The box edge in T: (s, +h_y, +h_z), s ∈ [−h_x, h_x], with its middle at p_edge_W_m.
  const Vector3d middle_T(0.0, knife.box.half_extents_m.y(), knife.box.half_extents_m.z());
  knife.X_WT = Pose(R, knife.p_edge_W_m - R * middle_T);
  return knife;
}

TEST(CollisionDetectionTest, ToolEdgeAcrossBodyEdgeMakesOneEdgeContact) {
  const fem::Model body = MakeReferenceBlock();
  const Eigen::VectorXd& x = body.rest_positions_m;
  {  // w is (d_tool × d_body)/|d_tool × d_body| for the edge directions u and x
    const KnifeEdge knife = MakeKnifeEdge(0.0);
    ASSERT_LT((knife.u.cross(Vector3d::UnitX()).normalized() - knife.w).norm(), 1e-15);
  }
  for (const double depth_m : {0.001, -0.0005}) {  // pushed in 1 mm; 0.5 mm clear (in margin)
    SCOPED_TRACE("depth " + std::to_string(depth_m));
    const KnifeEdge knife = MakeKnifeEdge(depth_m);
    DetectionOptions options;
    options.continuous = false;
    std::vector<Contact> contacts;
    options.edge_contacts = false;  // what the detector saw before: nothing at all
    CollisionDetector(body, knife.box, options).Detect(x, knife.X_WT, x, knife.X_WT, &contacts);
    EXPECT_TRUE(contacts.empty());

    options.edge_contacts = true;
    CollisionDetector detector(body, knife.box, options);
    detector.Detect(x, knife.X_WT, x, knife.X_WT, &contacts);
    ASSERT_EQ(contacts.size(), 1u);
    EXPECT_EQ(detector.statistics().num_edge_contacts, 1);
    const Contact& k = contacts.front();
    ASSERT_EQ(EdgeContacts(contacts).size(), 1u);
    // The segments' distance is |depth|, negative when the knife edge is inside the block; the
    // normal leaves the tool into the block's corner: +w.
    EXPECT_NEAR(k.gap_m, -depth_m, kExactTolerance_m);
    EXPECT_LT((k.n_W - knife.w).norm(), 1e-12);
    EXPECT_LT((k.p_body_W_m - knife.p_block_W_m).norm(), kExactTolerance_m);
    EXPECT_LT((k.p_tool_W_m - knife.p_edge_W_m).norm(), kExactTolerance_m);
    const Vector3d a = x.segment<3>(3 * k.nodes[0]), b = x.segment<3>(3 * k.nodes[1]);
    EXPECT_NEAR(std::abs(a.x() - b.x()), 0.01, 1e-15);  // the block edge's cell at x0
    EXPECT_LT((k.weights[0] * a + k.weights[1] * b - k.p_body_W_m).norm(), kExactTolerance_m);
    EXPECT_NEAR(k.weights[0] + k.weights[1], 1.0, 1e-15);
    EXPECT_EQ(k.weights[2], 0.0);
  }
}

// Every edge of a cube in turn across the block's edge, as the knife's is: each of the cube's 24
// rotations S, posed at X_WT S, puts the edge S⁻¹ e (e the knife's) where the knife's edge was,
// and each such pose makes the one edge contact. Every tool edge, whichever run of edges
// (CollisionDetector's kToolRun) its bounding sphere is checked in, is met: a run's
// sphere of radius 0, or left in T, fails it (one short by less than the pair test's own reach,
// half a body edge and the margin, would not).
TEST(CollisionDetectionTest, EveryToolEdgeMeetsTheBodyEdgeItCrosses) {
  const fem::Model body = MakeReferenceBlock();
  const Eigen::VectorXd& x = body.rest_positions_m;
  KnifeEdge knife = MakeKnifeEdge(0.001);
  const Vector3d middle_T(0.0, knife.box.half_extents_m.y(), knife.box.half_extents_m.z());
  knife.box.half_extents_m = Vector3d::Constant(0.01);  // a cube: its rotations map it onto itself
  knife.X_WT.translation() = knife.p_edge_W_m - knife.X_WT.linear() * middle_T;
  DetectionOptions options;
  options.continuous = false;
  CollisionDetector detector(body, knife.box, options);
  int poses = 0;
  std::array<int, 3> axes = {0, 1, 2};
  do {
    for (int signs = 0; signs < 8; ++signs) {
      Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
      for (int i = 0; i < 3; ++i) S(i, axes[i]) = (signs >> i & 1) ? -1.0 : 1.0;
      if (S.determinant() < 0.0) continue;
      SCOPED_TRACE("rotation " + std::to_string(poses));
      std::vector<Contact> contacts;
      detector.Detect(x, knife.X_WT * Isometry3d(S), x, knife.X_WT * Isometry3d(S), &contacts);
      ASSERT_EQ(EdgeContacts(contacts).size(), 1u);
      EXPECT_NEAR(EdgeContacts(contacts).front().gap_m, -0.001, kExactTolerance_m);
      ++poses;
    }
  } while (std::next_permutation(axes.begin(), axes.end()));
  EXPECT_EQ(poses, 24);
}

// The lowest edge of a box turned 45° about x lies along the block's top-front edge, 1 mm deep:
// the edges are parallel and the block's nodes on it are inside the box (node contacts hold the
// box). Turned 0.05 rad about z, the same edge crosses body edges and makes edge contacts.
TEST(CollisionDetectionTest, ParallelEdgesMakeNoEdgeContact) {
  const fem::Model body = MakeReferenceBlock();
  const Eigen::VectorXd& x = body.rest_positions_m;
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m = Vector3d(0.08, 0.01, 0.01);  // longer than the block
  const double depth_m = 0.001, h = box.half_extents_m.y();
  DetectionOptions options;
  options.continuous = false;
  for (const double yaw_rad : {0.0, 1e-7, 0.05}) {
    SCOPED_TRACE("yaw " + std::to_string(yaw_rad));
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(yaw_rad, Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(M_PI / 4.0, Vector3d::UnitX()))
                                  .matrix();
    // The edge at T's (·, −h, −h) is lowest; its middle goes to (0.0347, 0, 0.05 − depth).
    const Vector3d edge_middle_W(0.0347, 0.0, 0.05 - depth_m);
    const Isometry3d X_WT = Pose(R, edge_middle_W - R * Vector3d(0.0, -h, -h));
    CollisionDetector detector(body, box, options);
    std::vector<Contact> contacts;
    detector.Detect(x, X_WT, x, X_WT, &contacts);
    const std::vector<Contact> edges = EdgeContacts(contacts);
    if (yaw_rad < 1e-6) {
      EXPECT_GE(detector.statistics().num_node_contacts, 5);
      EXPECT_EQ(detector.statistics().num_edge_contacts, 0);
      EXPECT_TRUE(edges.empty());
    } else {
      EXPECT_GE(edges.size(), 1u);
      for (const Contact& k : edges) {  // across the top face's edges: straight down
        EXPECT_LT((k.n_W - Vector3d(0.0, 0.0, -1.0)).norm(), 1e-12);
        EXPECT_LT(k.gap_m, 0.0);
      }
    }
  }
}

// A box edge 0.5 mm under the top face, inside the block, crossing the face's edges: pointing
// down (the box above it) it presses on the face from outside and makes edge contacts; pointing
// up (the box below it, buried) it meets the face from behind (n along the faces' outward
// normal), where a positive gap would be wrong: no edge contact.
TEST(CollisionDetectionTest, EdgeBehindBodyFacesMakesNoEdgeContact) {
  const fem::Model body = MakeReferenceBlock();
  const Eigen::VectorXd& x = body.rest_positions_m;
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m = Vector3d(0.03, 0.01, 0.01);  // x ∈ [0.02, 0.08]: clear of the side faces
  const double h = box.half_extents_m.y();
  DetectionOptions options;
  options.continuous = false;
  for (const bool pointing_down : {true, false}) {
    SCOPED_TRACE(pointing_down ? "edge pointing down" : "edge pointing up");
    // The edge at T's (·, −h, −h) is lowest after 45° about x, highest after 225°.
    const double roll_rad = (pointing_down ? 0.25 : 1.25) * M_PI;
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.05, Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(roll_rad, Vector3d::UnitX()))
                                  .matrix();
    const Isometry3d X_WT = Pose(R, Vector3d(0.05, 0.0347, 0.0495) - R * Vector3d(0.0, -h, -h));
    CollisionDetector detector(body, box, options);
    std::vector<Contact> contacts;
    detector.Detect(x, X_WT, x, X_WT, &contacts);
    const std::vector<Contact> edges = EdgeContacts(contacts);
    if (pointing_down) {  // the lowest edge under the face's edges; near misses of the end edges
      EXPECT_GE(std::count_if(edges.begin(), edges.end(),
                              [](const Contact& k) {
                                return std::abs(k.gap_m + 0.0005) < kExactTolerance_m &&
                                       (k.n_W - Vector3d(0.0, 0.0, -1.0)).norm() < 1e-12;
                              }),
                5);
    } else {
      EXPECT_TRUE(edges.empty());
    }
  }
}

// Flat against the body. A 4 × 4 cm box face pressed 0.5 mm into the top face: every body edge
// crossing its rim lies flat against it and has a node under it in contact, which holds the
// face: no edge contacts. A 2 mm wide blade face, longer than the block, pressed 0.5 mm between
// two rows of nodes: no node is under it and no corner over the body, so only the body edges
// crossing its two long edges hold it (without them it would sink).
TEST(CollisionDetectionTest, FlatFaceNeedsEdgeContactsOnlyWhereNoNodeIsUnderIt) {
  const fem::Model body = MakeReferenceBlock();
  const Eigen::VectorXd& x = body.rest_positions_m;
  DetectionOptions options;
  options.continuous = false;
  const double depth_m = 0.0005;
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m = Vector3d(0.02, 0.02, 0.01);
  const Isometry3d X_box =
      Pose(Eigen::Matrix3d::Identity(), Vector3d(0.0503, 0.0497, 0.06 - depth_m));
  CollisionDetector box_detector(body, box, options);
  std::vector<Contact> contacts;
  box_detector.Detect(x, X_box, x, X_box, &contacts);
  EXPECT_EQ(std::count_if(contacts.begin(), contacts.end(),  // the 4 × 4 nodes under the face
                          [](const Contact& k) { return k.nodes[1] < 0 && k.gap_m < 0.0; }),
            16);
  EXPECT_EQ(box_detector.statistics().num_edge_contacts, 0);

  ToolShape blade;
  blade.kind = ToolShape::Kind::kBox;
  blade.half_extents_m = Vector3d(0.06, 0.001, 0.01);  // x ∈ [−0.01, 0.11], y ∈ ±1 mm
  const Isometry3d X_blade =
      Pose(Eigen::Matrix3d::Identity(), Vector3d(0.05, 0.0347, 0.06 - depth_m));
  for (const bool edges : {false, true}) {
    options.edge_contacts = edges;
    CollisionDetector detector(body, blade, options);
    detector.Detect(x, X_blade, x, X_blade, &contacts);
    if (!edges) {
      EXPECT_TRUE(contacts.empty());
      continue;
    }
    // 11 body edges along y (x = 0, 1, …, 10 cm) and the diagonals of the cells under the blade,
    // each crossing both long edges of its bottom face.
    EXPECT_GE(contacts.size(), 2u * 11u);
    EXPECT_EQ(EdgeContacts(contacts).size(), contacts.size());
    for (const Contact& k : contacts) {
      EXPECT_NEAR(k.gap_m, -depth_m, kExactTolerance_m);
      EXPECT_LT((k.n_W - Vector3d(0.0, 0.0, -1.0)).norm(), 1e-12);
      EXPECT_NEAR(std::abs(k.p_tool_W_m.y() - 0.0347), 0.001, kExactTolerance_m);
    }
  }
}

// c = J_v v + J_ω ω + J_u u̇ is the rate of the gap of the two segments' lines, φ = (b − a)·n
// with a, b any points of the tool and body lines and n their unit common normal: the edge
// contact's row against a central difference of φ as the tool translates and rotates about its
// centre of mass and the two body nodes move.
TEST(CollisionDetectionTest, EdgeContactJacobianIsTheGapRate) {
  const fem::Model body = MakeReferenceBlock();
  const Eigen::VectorXd& x = body.rest_positions_m;
  const KnifeEdge knife = MakeKnifeEdge(0.001);
  DetectionOptions options;
  options.continuous = false;
  CollisionDetector detector(body, knife.box, options);
  std::vector<Contact> contacts;
  detector.Detect(x, knife.X_WT, x, knife.X_WT, &contacts);
  ASSERT_EQ(contacts.size(), 1u);
  const Contact& k = contacts.front();
  const Vector3d v(0.1, -0.2, 0.3), w(0.5, -0.3, 0.2);
  Eigen::VectorXd u_dot = Eigen::VectorXd::Zero(body.num_dofs());
  u_dot.segment<3>(3 * k.nodes[0]) = Vector3d(-0.2, 0.4, 0.1);
  u_dot.segment<3>(3 * k.nodes[1]) = Vector3d(0.3, 0.1, -0.5);
  const Vector3d edge_T[2] = {Vector3d(-0.02, 0.01, 0.01), Vector3d(0.02, 0.01, 0.01)};
  const auto gap = [&](double tau) {
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(w.norm() * tau, w.normalized()) * knife.X_WT.linear();
    const Vector3d x_tool = knife.X_WT.translation() + tau * v;
    const Vector3d a0 = x_tool + R * edge_T[0], a1 = x_tool + R * edge_T[1];
    const Vector3d b0 = x.segment<3>(3 * k.nodes[0]) + tau * u_dot.segment<3>(3 * k.nodes[0]);
    const Vector3d b1 = x.segment<3>(3 * k.nodes[1]) + tau * u_dot.segment<3>(3 * k.nodes[1]);
    Vector3d n = (a1 - a0).cross(b1 - b0).normalized();
    if (n.dot(k.n_W) < 0.0) n = -n;
    return (b0 - a0).dot(n);
  };
  EXPECT_NEAR(gap(0.0), k.gap_m, kExactTolerance_m);
  const double step_s = 1e-6;
  const double rate_m_s = (gap(step_s) - gap(-step_s)) / (2.0 * step_s);
  const std::vector<std::uint8_t> fixed(body.num_dofs(), 0);
  const ContactJacobian J =
      CalcContactJacobian(contacts, knife.X_WT.translation(), 1, body.num_dofs(), fixed);
  const double c_m_s = J.J_v.row(0).dot(v) + J.J_w.row(0).dot(w) + (J.J_u * u_dot)[0];
  // Central difference: truncation O(step²) ≈ 1e-12 m/s; round-off ε·0.1 m / step ≈ 1e-11 m/s.
  EXPECT_NEAR(c_m_s, rate_m_s, 1e-6 * std::abs(rate_m_s));
  EXPECT_GT(std::abs(rate_m_s), 0.1);  // the motion does move the gap
}

TEST(CollisionDetectionTest, RejectsBadInput) {
  const fem::Model body = MakeBlock(Vector3d::Constant(0.01), {1, 1, 1});
  ToolShape sphere;
  sphere.radius_m = 0.01;
  DetectionOptions options;
  options.margin_m = -1e-3;
  EXPECT_THROW(CollisionDetector(body, sphere, options), std::invalid_argument);
  CollisionDetector detector(body, sphere, DetectionOptions{});
  std::vector<Contact> contacts;
  const Eigen::VectorXd too_short = Eigen::VectorXd::Zero(3);
  EXPECT_THROW(detector.Detect(too_short, Isometry3d::Identity(), too_short, Isometry3d::Identity(),
                               &contacts),
               std::invalid_argument);
}

}  // namespace
}  // namespace hapsim::contact
