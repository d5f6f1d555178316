// Contacts on a body of quadratic tets (contact/quadratic_surface.h): a sphere pressed onto the
// boundary of a straight quadratic block, the contact found on a sub-triangle, against the same
// contact computed by brute force: the boundary face of the linear mesh under the point found by
// a search over every tet's faces, the point's coordinates in it, and the six quadratic shape
// functions there evaluated here. Also: the weights reproduce a quadratic field over the face
// (the sub-triangle's linear weights would not), and a deformed body moves the contact point as
// its quadratic field does.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <map>
#include <vector>

#include "contact/collision_detection.h"
#include "fem/lattice_mesher.h"
#include "fem/model.h"
#include "fem/quadratic_tet.h"

namespace hapsim::contact {
namespace {

using Eigen::Isometry3d;
using Eigen::Vector3d;

struct Block {
  fem::TetMesh linear;
  fem::Model model;
};

Block MakeBlock() {
  Block setup;
  setup.linear =
      fem::MakeBoxTetMesh(Vector3d::Zero(), Vector3d(0.02, 0.02, 0.01), Eigen::Vector3i(2, 2, 1));
  fem::Material material;
  setup.model = fem::MakeModel(fem::MakeQuadraticMesh(setup.linear), material, {});
  return setup;
}

// The contact a sphere of 5 mm pressed 0.5 mm into the top face above (x, y) makes by its centre:
// of those on more than one node (faces and edges), the one nearest below the centre.
Contact PressTop(const fem::Model& model, const Eigen::VectorXd& x_m, double x, double y) {
  ToolShape sphere;
  sphere.kind = ToolShape::Kind::kSphere;
  sphere.radius_m = 0.005;
  Isometry3d X_WT = Isometry3d::Identity();
  X_WT.translation() = Vector3d(x, y, 0.01 + 0.005 - 5e-4);
  DetectionOptions options;
  options.margin_m = 0.0;
  std::vector<Contact> contacts;
  CollisionDetector(model, sphere, options).Detect(x_m, X_WT, x_m, X_WT, &contacts);
  const Contact* nearest = nullptr;
  const auto offset = [&](const Contact& c) {
    return (c.p_body_W_m.head<2>() - Eigen::Vector2d(x, y)).norm();
  };
  for (const Contact& contact : contacts)
    if (contact.nodes[1] >= 0 && (nearest == nullptr || offset(contact) < offset(*nearest)))
      nearest = &contact;
  if (nearest == nullptr) {
    ADD_FAILURE() << "no face contact among " << contacts.size();
    return Contact();
  }
  return *nearest;
}

std::map<int, double> WeightsByNode(const Contact& contact) {
  std::map<int, double> weights;
  for (int k = 0; k < kMaxContactNodes && contact.nodes[k] >= 0; ++k)
    weights[contact.nodes[k]] += contact.weights[k];
  return weights;
}

// Brute force: the tet face of the linear mesh on the top (z = 1 cm) whose triangle holds p,
// its face coordinates (s, t), and the quadratic weights of its corners and edge nodes.
std::map<int, double> BruteForceWeights(const Block& setup, const Vector3d& p) {
  const fem::TetMesh& mesh = setup.model.mesh;
  static constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  for (int t = 0; t < mesh.num_tets(); ++t)
    for (const auto& face : kFaces) {
      Vector3d c[3];
      bool on_top = true;
      for (int k = 0; k < 3; ++k) {
        c[k] = mesh.rest_positions_m.col(mesh.tets(face[k], t));
        on_top = on_top && std::abs(c[k].z() - 0.01) < 1e-12;
      }
      if (!on_top) continue;
      Eigen::Matrix<double, 3, 2> E;
      E << c[1] - c[0], c[2] - c[0];
      const Eigen::Vector2d st = E.colPivHouseholderQr().solve(p - c[0]);
      const double L[3] = {1.0 - st.sum(), st[0], st[1]};
      if (L[0] < -1e-12 || L[1] < -1e-12 || L[2] < -1e-12) continue;
      std::map<int, double> weights;
      for (int k = 0; k < 3; ++k) {
        weights[mesh.tets(face[k], t)] += L[k] * (2.0 * L[k] - 1.0);
        const int edge = fem::FindP2Edge(face[k], face[(k + 1) % 3]);
        weights[mesh.edge_nodes(edge, t)] += 4.0 * L[k] * L[(k + 1) % 3];
      }
      return weights;
    }
  ADD_FAILURE() << "no top face holds the point";
  return {};
}

TEST(QuadraticSurface, AContactCarriesTheFacesQuadraticShapeFunctions) {
  const Block setup = MakeBlock();
  const Eigen::VectorXd& X = setup.model.rest_positions_m;
  for (const auto& [x, y] :
       {std::pair{0.0071, 0.0123}, std::pair{0.0133, 0.0042}, std::pair{0.0049, 0.0061}}) {
    const Contact contact = PressTop(setup.model, X, x, y);
    const std::map<int, double> weights = WeightsByNode(contact);
    double sum = 0.0;
    Vector3d p = Vector3d::Zero();
    for (const auto& [node, w] : weights) {
      sum += w;
      p += w * X.segment<3>(3 * node);
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
    // On the flat face of a straight element the quadratic point is the sub-triangle's point.
    EXPECT_LT((p - contact.p_body_W_m).norm(), 1e-12);
    EXPECT_LT((p - Vector3d(x, y, 0.01)).norm(), 1e-12);
    // Against brute force, node by node.
    const std::map<int, double> expected = BruteForceWeights(setup, p);
    for (const auto& [node, w] : expected) {
      const auto found = weights.find(node);
      const double got = found == weights.end() ? 0.0 : found->second;
      EXPECT_NEAR(got, w, 1e-12) << "node " << node << " at " << x << ", " << y;
    }
    EXPECT_GT(weights.size(), 3u) << "inside a face: more than a sub-triangle's corners";
    // A quadratic field over the face is reproduced exactly.
    const auto f = [](const Vector3d& q) {
      return 3e4 * (q.x() - 0.01) * (q.x() - 0.01) - 5e4 * (q.x() - 0.01) * (q.y() - 0.003) +
             2e4 * q.y() * q.y() + q.x();
    };
    double interpolated = 0.0;
    for (const auto& [node, w] : weights) interpolated += w * f(X.segment<3>(3 * node));
    EXPECT_NEAR(interpolated, f(p), 1e-12);
  }
}

// A deformed body: the contact row moves its point with the quadratic field. Every node is
// displaced by a quadratic field u(X); the contact found on the deformed body has weights whose
// point Σ w (X + u(X)) lies on the quadratic face (the field's image of the face), here within
// the flat sub-triangle's distance from it, O(h² curvature), and the row is the brute-force one at
// the rest point with the same face coordinates.
TEST(QuadraticSurface, OnADeformedBodyTheRowMovesThePointAsTheQuadraticField) {
  const Block setup = MakeBlock();
  const Eigen::VectorXd& X = setup.model.rest_positions_m;
  const auto u = [](const Vector3d& q) {
    return Vector3d(0.0, 0.0,
                    -5.0 * ((q.x() - 0.01) * (q.x() - 0.01) + (q.y() - 0.01) * (q.y() - 0.01)));
  };
  Eigen::VectorXd x = X;
  for (int n = 0; n < setup.model.num_nodes(); ++n) x.segment<3>(3 * n) += u(X.segment<3>(3 * n));
  const Contact contact = PressTop(setup.model, x, 0.0071, 0.0123);
  const std::map<int, double> weights = WeightsByNode(contact);
  Vector3d rest_point = Vector3d::Zero(), moved_point = Vector3d::Zero();
  for (const auto& [node, w] : weights) {
    rest_point += w * X.segment<3>(3 * node);
    moved_point += w * x.segment<3>(3 * node);
  }
  // The quadratic field is reproduced: the moved point is the rest point moved by u.
  EXPECT_LT((moved_point - (rest_point + u(rest_point))).norm(), 1e-12);
  // Brute force at the rest point (face coordinates are the same on the deformed body).
  const std::map<int, double> expected = BruteForceWeights(setup, rest_point);
  for (const auto& [node, w] : expected) {
    const auto found = weights.find(node);
    EXPECT_NEAR(found == weights.end() ? 0.0 : found->second, w, 1e-12) << "node " << node;
  }
  // The flat sub-triangle's point, where the gap was measured, is near the curved face's.
  EXPECT_LT((moved_point - contact.p_body_W_m).norm(), 1e-4);
}

}  // namespace
}  // namespace hapsim::contact
