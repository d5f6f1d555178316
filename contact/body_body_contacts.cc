#include "contact/body_body_contacts.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <limits>
#include <numeric>

#include "core/closest_points.h"

namespace hapsim::contact {
namespace {

// Union–find root of `node`, with path halving.
int FindRoot(std::vector<int>* parent, int node) {
  while ((*parent)[node] != node) {
    (*parent)[node] = (*parent)[(*parent)[node]];
    node = (*parent)[node];
  }
  return node;
}

// The box around `nodes` at x_m, each node's box grown by grow_m(node).
template <typename Grow>
Eigen::AlignedBox3d BoundNodes(const std::vector<int>& nodes, const Eigen::VectorXd& x_m,
                               const Grow& grow_m) {
  Eigen::AlignedBox3d box;
  for (int node : nodes) {
    const Eigen::Vector3d p = x_m.segment<3>(3 * node);
    const Eigen::Vector3d g = Eigen::Vector3d::Constant(grow_m(node));
    box.extend(p - g);
    box.extend(p + g);
  }
  return box;
}

}  // namespace

BodyBodyContacts::BodyBodyContacts(const fem::Model& body, double margin_m)
    : body_(body), margin_m_(margin_m) {
  const fem::TetMesh& mesh = body.mesh;
  std::vector<int> parent(static_cast<size_t>(mesh.num_nodes()));
  std::iota(parent.begin(), parent.end(), 0);
  for (int t = 0; t < mesh.num_tets(); ++t)
    for (int a = 1; a < mesh.nodes_per_tet(); ++a)
      parent[FindRoot(&parent, mesh.node(a, t))] = FindRoot(&parent, mesh.node(0, t));
  // Objects numbered in the order of their first node (the order MergeModels stacked them).
  std::vector<int> object_of_root(parent.size(), -1);
  object_of_node_.assign(parent.size(), -1);
  int num_objects = 0;
  for (int node = 0; node < mesh.num_nodes(); ++node) {
    int& object = object_of_root[FindRoot(&parent, node)];
    if (object < 0) object = num_objects++;
    object_of_node_[node] = object;
  }
  surface_nodes_.resize(num_objects);
  triangles_.resize(num_objects);
  std::vector<std::uint8_t> on_surface(parent.size(), 0);
  for (int f = 0; f < body.surface_triangles.cols(); ++f) {
    triangles_[object_of_node_[body.surface_triangles(0, f)]].push_back(f);
    for (int k = 0; k < 3; ++k) on_surface[body.surface_triangles(k, f)] = 1;
  }
  for (int node = 0; node < mesh.num_nodes(); ++node)
    if (on_surface[node] && !body.dof_is_fixed[3 * node])
      surface_nodes_[object_of_node_[node]].push_back(node);
}

template <typename Visit, typename Threshold>
void BodyBodyContacts::ForEachCandidate(const Eigen::VectorXd& x_m, const Threshold& threshold,
                                        const Visit& visit) const {
  const int n = num_objects();
  if (n < 2) return;
  const Matrix3Xi& faces = body_.surface_triangles;
  std::vector<Eigen::AlignedBox3d> boxes(n);
  for (int o = 0; o < n; ++o) boxes[o] = BoundNodes(surface_nodes_[o], x_m, threshold);
  std::vector<int> near_faces;
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      if (a == b || !boxes[a].intersects(boxes[b])) continue;
      const Eigen::AlignedBox3d overlap = boxes[a].intersection(boxes[b]);
      // B's faces that reach into the overlap (a face touches it if any of its corners' boxes do).
      near_faces.clear();
      for (int f : triangles_[b]) {
        Eigen::AlignedBox3d face;
        for (int k = 0; k < 3; ++k) face.extend(Eigen::Vector3d(x_m.segment<3>(3 * faces(k, f))));
        if (overlap.intersects(face)) near_faces.push_back(f);
      }
      if (near_faces.empty()) continue;
      for (int node : surface_nodes_[a]) {
        const Eigen::Vector3d p = x_m.segment<3>(3 * node);
        if (!overlap.contains(p)) continue;
        // The nearest of B's faces, if within reach. Faces as near (a node facing B's edge, the
        // edge's two faces at one distance) go to the one the node lies most in front of: a side
        // face's normal is square to the separation and would measure no gap.
        double best_m = threshold(node), best_facing = -2.0;
        int best_face = -1;
        TrianglePoint best;
        for (int f : near_faces) {
          const Eigen::Vector3d a = x_m.segment<3>(3 * faces(0, f));
          const Eigen::Vector3d b = x_m.segment<3>(3 * faces(1, f));
          const Eigen::Vector3d c = x_m.segment<3>(3 * faces(2, f));
          const TrianglePoint q = CalcClosestPointOnTriangle(p, a, b, c);
          const double distance_m = (p - q.point).norm();
          const double facing =
              distance_m > 0.0 ? (p - q.point).dot((b - a).cross(c - a).normalized()) / distance_m
                               : 1.0;
          const double tie_m = 1e-9 + 1e-6 * distance_m;
          if (distance_m < best_m - tie_m ||
              (distance_m <= best_m + tie_m && facing > best_facing)) {
            best_m = std::min(best_m, distance_m);
            best_facing = facing, best_face = f, best = q;
          }
        }
        if (best_face >= 0) visit(node, best_face, best, b);
      }
    }
  }
}

void BodyBodyContacts::AddContacts(const Eigen::VectorXd& x_start_m, const Eigen::VectorXd& x_end_m,
                                   std::vector<Contact>* contacts) const {
  if (num_objects() < 2) return;
  const Matrix3Xi& faces = body_.surface_triangles;
  // Reach: the margin and how far a node moves over the frame, on either side (a face moves as
  // fast as its nodes; the largest sweep of the body bounds that).
  double largest_sweep_m = 0.0;
  for (const std::vector<int>& nodes : surface_nodes_)
    for (int node : nodes)
      largest_sweep_m = std::max(
          largest_sweep_m, (x_end_m.segment<3>(3 * node) - x_start_m.segment<3>(3 * node)).norm());
  const auto threshold = [&](int node) {
    return margin_m_ + largest_sweep_m +
           (x_end_m.segment<3>(3 * node) - x_start_m.segment<3>(3 * node)).norm();
  };
  ForEachCandidate(x_start_m, threshold,
                   [&](int node, int f, const TrianglePoint& q, int /*face_object*/) {
                     const Eigen::Vector3d a = x_start_m.segment<3>(3 * faces(0, f));
                     const Eigen::Vector3d b = x_start_m.segment<3>(3 * faces(1, f));
                     const Eigen::Vector3d c = x_start_m.segment<3>(3 * faces(2, f));
                     const Eigen::Vector3d normal = (b - a).cross(c - a);
                     if (!(normal.norm() > 0.0)) return;  // a collapsed face: no direction
                     Contact contact;
                     contact.on_tool = false;
                     contact.n_W = normal.normalized();  // out of the face's object
                     contact.p_tool_W_m = q.point;
                     contact.p_body_W_m = x_start_m.segment<3>(3 * node);
                     contact.gap_m = (contact.p_body_W_m - q.point).dot(contact.n_W);
                     contact.SetBodyNodes({node, faces(0, f), faces(1, f), faces(2, f)},
                                          {1.0, -q.weights[0], -q.weights[1], -q.weights[2]});
                     contacts->push_back(contact);
                   });
}

std::optional<BodyBodyContacts::Overlap> BodyBodyContacts::FindDeepestOverlap(
    const Eigen::VectorXd& x_m, double tolerance_m) const {
  const Matrix3Xi& faces = body_.surface_triangles;
  // Nodes within 10 mm of another object's faces: an overlap deeper than that is seen from the
  // faces nearest the node, which may be the far side's, and still reported, shallower.
  constexpr double kReach_m = 0.01;
  std::optional<Overlap> deepest;
  ForEachCandidate(
      x_m, [&](int) { return std::max(margin_m_, kReach_m); },
      [&](int node, int f, const TrianglePoint& q, int face_object) {
        const Eigen::Vector3d a = x_m.segment<3>(3 * faces(0, f));
        const Eigen::Vector3d normal =
            (x_m.segment<3>(3 * faces(1, f)) - a).cross(x_m.segment<3>(3 * faces(2, f)) - a);
        const double depth_m = -(x_m.segment<3>(3 * node) - q.point).dot(normal.normalized());
        if (depth_m > tolerance_m && (!deepest || depth_m > deepest->depth_m))
          deepest = Overlap{object_of_node(node), face_object, node, faces(0, f), depth_m};
      });
  return deepest;
}

}  // namespace hapsim::contact
