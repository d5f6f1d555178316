#include "contact/body_body_contacts.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <limits>

#include "core/closest_points.h"

namespace hapsim::contact {
BodyBodyContacts::BodyBodyContacts(const fem::Model& body, double margin_m)
    : body_(body), margin_m_(margin_m) {
  const int num_objects = body.num_objects();
  object_of_node_.assign(static_cast<size_t>(body.num_nodes()), 0);
  for (int o = 1; o < num_objects; ++o)
    std::fill(object_of_node_.begin() + body.object_first_node(o),
              object_of_node_.begin() + body.object_end_node(o), o);
  surface_nodes_.resize(num_objects);
  triangles_.resize(num_objects);
  for (int f = 0; f < body.surface_triangles.cols(); ++f)
    triangles_[object_of_node_[body.surface_triangles(0, f)]].push_back(f);
  for (int node : fem::FindFreeSurfaceNodes(body))
    surface_nodes_[object_of_node_[node]].push_back(node);
}

template <typename Visit, typename Threshold>
void BodyBodyContacts::ForEachCandidate(const Eigen::VectorXd& x_m, const Threshold& threshold,
                                        const Visit& visit) const {
  const int n = num_objects();
  if (n < 2) return;
  const Matrix3Xi& faces = body_.surface_triangles;
  const auto corner = [&](int f, int k) -> Eigen::Vector3d {
    return x_m.segment<3>(3 * faces(k, f));
  };
  // Each object's free surface nodes, each grown by its reach; and its faces, whole.
  std::vector<Eigen::AlignedBox3d> node_boxes(n), face_boxes(n);
  for (int o = 0; o < n; ++o) {
    for (int node : surface_nodes_[o]) {
      const Eigen::Vector3d p = x_m.segment<3>(3 * node);
      const Eigen::Vector3d reach = Eigen::Vector3d::Constant(threshold(node));
      node_boxes[o].extend(p - reach);
      node_boxes[o].extend(p + reach);
    }
    for (int f : triangles_[o])
      for (int k = 0; k < 3; ++k) face_boxes[o].extend(corner(f, k));
  }
  std::vector<int> near_faces;
  for (int node_object = 0; node_object < n; ++node_object) {
    for (int face_object = 0; face_object < n; ++face_object) {
      if (node_object == face_object ||
          !node_boxes[node_object].intersects(face_boxes[face_object]))
        continue;
      // A face within a node's reach has its nearest point in the node's grown box, so in the
      // overlap: the faces that reach into it, and the nodes whose grown box meets them.
      const Eigen::AlignedBox3d overlap =
          node_boxes[node_object].intersection(face_boxes[face_object]);
      near_faces.clear();
      for (int f : triangles_[face_object]) {
        Eigen::AlignedBox3d face;
        for (int k = 0; k < 3; ++k) face.extend(corner(f, k));
        if (overlap.intersects(face)) near_faces.push_back(f);
      }
      if (near_faces.empty()) continue;
      for (int node : surface_nodes_[node_object]) {
        const Eigen::Vector3d p = x_m.segment<3>(3 * node);
        if (overlap.exteriorDistance(p) > threshold(node)) continue;
        // Faces as near (a node facing an edge: the edge's two faces at one distance) go to the
        // one the node lies most in front of: a side face's normal is square to the separation
        // and would measure no gap.
        double best_m = threshold(node), best_facing = -2.0;
        int best_face = -1;
        TrianglePoint best;
        Eigen::Vector3d best_normal = Eigen::Vector3d::UnitZ();
        for (int f : near_faces) {
          const Eigen::Vector3d area =
              (corner(f, 1) - corner(f, 0)).cross(corner(f, 2) - corner(f, 0));
          if (!(area.norm() > 0.0)) continue;  // a collapsed face: no direction
          const Eigen::Vector3d normal = area.normalized();
          const TrianglePoint q =
              CalcClosestPointOnTriangle(p, corner(f, 0), corner(f, 1), corner(f, 2));
          const double distance_m = (p - q.point).norm();
          const double facing = distance_m > 0.0 ? (p - q.point).dot(normal) / distance_m : 1.0;
          const double tie_m = 1e-9 + 1e-6 * distance_m;
          if (distance_m < best_m - tie_m ||
              (distance_m <= best_m + tie_m && facing > best_facing)) {
            best_m = std::min(best_m, distance_m);
            best_facing = facing, best_face = f, best = q, best_normal = normal;
          }
        }
        if (best_face >= 0) visit(node, best_face, best, best_normal, face_object);
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
                   [&](int node, int f, const TrianglePoint& q, const Eigen::Vector3d& normal,
                       int /*face_object*/) {
                     Contact contact;
                     contact.on_tool = false;
                     contact.n_W = normal;  // out of the face's object
                     contact.p_tool_W_m = q.point;
                     contact.p_body_W_m = x_start_m.segment<3>(3 * node);
                     contact.gap_m = (contact.p_body_W_m - q.point).dot(normal);
                     contact.SetBodyNodes({node, faces(0, f), faces(1, f), faces(2, f)},
                                          {1.0, -q.weights[0], -q.weights[1], -q.weights[2]});
                     contacts->push_back(contact);
                   });
}

std::optional<BodyBodyContacts::Overlap> BodyBodyContacts::FindDeepestOverlap(
    const Eigen::VectorXd& x_m, double tolerance_m) const {
  // Nodes within 10 mm of another object's faces: an overlap deeper than that is seen from the
  // faces nearest the node, which may be the far side's, and still reported, shallower.
  constexpr double kReach_m = 0.01;
  std::optional<Overlap> deepest;
  ForEachCandidate(
      x_m, [&](int) { return std::max(margin_m_, kReach_m); },
      [&](int node, int /*face*/, const TrianglePoint& q, const Eigen::Vector3d& normal,
          int face_object) {
        const double depth_m = -(x_m.segment<3>(3 * node) - q.point).dot(normal);
        if (depth_m > tolerance_m && (!deepest || depth_m > deepest->depth_m))
          deepest = Overlap{object_of_node(node), face_object, depth_m};
      });
  return deepest;
}

}  // namespace hapsim::contact
