// Narrow phase (c) of CollisionDetector (collision_detection.h, pipeline step 5): tool edge
// versus body edge. A tool edge pressed across a body face between the face's nodes, with no
// body node inside the tool and no tool corner over the face, is seen by neither the node stage
// nor the feature stage: only the pair of edges sees it. Closest points of two segments: Ericson,
// Real-Time Collision Detection, §5.1.9; their normal d_tool × d_body is the edge–edge axis of
// the separating-axis test (§5.2.1). The pair is the closest pair of features only when that
// normal lies in both edges' normal cones; on the tool side this is checked exactly (so a
// negative gap means the body edge's point is inside the tool's wedge at that edge), on the body
// side only as "faces the tool" (n·m < 0 for one of its faces), because on a flat stretch of the
// body the cone is a single direction and a tilted tool edge would never match it.
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "contact/collision_detection.h"

namespace hapsim::contact {
namespace {

using Eigen::Vector3d;

// Closest-point parameters within this of 0 or 1 are end points: the node-versus-tool and
// feature-versus-face stages own those contacts.
constexpr double kEndpointParameter = 1e-6;

// |d_tool × d_body| below this fraction of |d_tool| |d_body| (edges within 1e-6 rad of parallel):
// the common normal is ill-defined, and the end points of the overlap are node or feature
// contacts.
constexpr double kMinSine = 1e-6;

// A normal on the boundary of the tool edge's cone (a body edge parallel to a tool face, e.g. a
// flat box face resting on a flat stretch of the body) is accepted despite round-off.
constexpr double kConeCosineSlack = 1e-9;

// n within this angle of one of the tool edge's face normals: the body edge lies flat against
// that face (its slope off the face ≤ the angle). If the body edge's node on that face's side has
// a node contact, that contact holds the face against the body edge to within (edge length) ×
// angle, 12 µm on a 1.2 cm edge, and the edge contact is redundant: without this, a face resting
// flat on the body adds one at every body edge crossing its rim (a box at rest in
// visual_frame_test: 13 → 33 contacts). A face narrower than the body's edges (a blade's tip)
// has no node under it, and keeps its edge contacts.
const double kFlushCosine = std::cos(1e-3);

// Two tool faces whose outward normals have m1·m2 above this are coplanar (a mesh's face
// diagonal): the edge between them is no feature.
constexpr double kCoplanarCosine = 1.0 - 1e-12;

bool IsInterior(double parameter) {
  return parameter > kEndpointParameter && parameter < 1.0 - kEndpointParameter;
}

// The wedge of outward normals between faces m1 and m2 (unit, both ⟂ the edge), as its unit
// bisector and the cosine of its half-angle. False for coplanar or opposite faces.
bool MakeEdgeCone(const Vector3d& m1, const Vector3d& m2, Vector3d* axis, double* cosine) {
  const Vector3d sum = m1 + m2;
  if (!(m1.dot(m2) < kCoplanarCosine) || !(sum.norm() > 1e-9)) return false;
  *axis = sum.normalized();
  *cosine = m1.dot(*axis);
  return true;
}

// The two faces' outward normals at each tool feature edge, in T (columns 2e and 2e + 1), and
// whether the edge is convex. Box: the two axes other than the edge's, signed as its corners.
// Cylinder rim segment: radial at its midpoint and ±z. Mesh: its two triangles.
void CalcToolEdgeFaceNormals(const ToolShape& shape, const ToolFeatures& features,
                             Matrix3Xd* normals, std::vector<char>* convex) {
  const Eigen::Index num_edges = features.edges.cols();
  normals->setZero(3, 2 * num_edges);
  convex->assign(num_edges, 1);
  std::map<std::pair<int, int>, std::vector<int>> edge_triangles;  // kMesh: edge → triangles
  const Matrix3Xi& triangles = shape.mesh.triangles;
  const Matrix3Xd& vertices = shape.mesh.vertices_m;
  if (shape.kind == ToolShape::Kind::kMesh)
    for (Eigen::Index f = 0; f < triangles.cols(); ++f)
      for (int k = 0; k < 3; ++k) {
        const int i = triangles(k, f), j = triangles((k + 1) % 3, f);
        edge_triangles[{std::min(i, j), std::max(i, j)}].push_back(static_cast<int>(f));
      }
  const auto face_normal = [&](int f) {
    const Vector3d a = vertices.col(triangles(0, f));
    return Vector3d((vertices.col(triangles(1, f)) - a).cross(vertices.col(triangles(2, f)) - a))
        .normalized();
  };
  for (Eigen::Index e = 0; e < num_edges; ++e) {
    const int i = features.edges(0, e), j = features.edges(1, e);
    const Vector3d p = features.vertices_T_m.col(i), q = features.vertices_T_m.col(j);
    Vector3d m1, m2;
    if (shape.kind == ToolShape::Kind::kBox) {  // corners differ along one axis only
      Eigen::Index along;
      (q - p).cwiseAbs().maxCoeff(&along);
      const Eigen::Index a = (along + 1) % 3, b = (along + 2) % 3;
      m1 = std::copysign(1.0, p[a]) * Vector3d::Unit(a);
      m2 = std::copysign(1.0, p[b]) * Vector3d::Unit(b);
    } else if (shape.kind == ToolShape::Kind::kCylinder) {
      const Vector3d middle = 0.5 * (p + q);
      m1 = Vector3d(middle.x(), middle.y(), 0.0).normalized();
      m2 = std::copysign(1.0, middle.z()) * Vector3d::UnitZ();
    } else {  // kMesh; MakeToolFeatures has checked that every edge has two triangles
      const std::vector<int>& two = edge_triangles.at({std::min(i, j), std::max(i, j)});
      m1 = face_normal(two[0]);
      m2 = face_normal(two[1]);
      // Convex when the second triangle's third vertex lies behind the first one's plane.
      const Vector3d third =
          vertices.col(triangles(0, two[1]) + triangles(1, two[1]) + triangles(2, two[1]) - i - j);
      (*convex)[e] = (third - p).dot(m1) < 0.0;
    }
    normals->col(2 * e) = m1;
    normals->col(2 * e + 1) = m2;
  }
}

// One body edge at the current positions.
struct BodyEdge {
  Vector3d a, b;                         // end points, world, m
  std::array<Vector3d, 2> face_normals;  // of its triangles (not normalised; 0 if none)
  std::array<int, 2> nodes;
};

// One sharp tool edge in world.
struct ToolEdge {
  Vector3d p, q;                         // end points, m
  Vector3d axis;                         // unit bisector of its faces' normals
  std::array<Vector3d, 2> face_normals;  // unit, outward
  double cone_cosine = 1.0;              // of the half-angle between them
};

// The edge contact of `tool` with `body`, gap unchecked; false when the pair makes none
// (collision_detection.h, step 5). *flush_node: the body edge's node on the side of a tool face
// that n lies within the flush angle of (kFlushCosine), else −1.
bool CalcEdgeContact(const ToolEdge& tool, const BodyEdge& body, Contact* contact,
                     int* flush_node) {
  const SegmentPoints closest = CalcClosestPointsOfSegments(tool.p, tool.q, body.a, body.b);
  if (!IsInterior(closest.s) || !IsInterior(closest.t)) return false;
  const Vector3d d_tool = tool.q - tool.p, d_body = body.b - body.a;
  Vector3d n = d_tool.cross(d_body);
  const double sine_scaled = n.norm();
  if (!(sine_scaled > kMinSine * d_tool.norm() * d_body.norm())) return false;
  n /= sine_scaled;
  // Out of the tool: towards the cone, then inside it (else a tool face is nearer the body edge
  // than the tool edge is, and a negative gap would not mean the body edge is inside the tool).
  if (n.dot(tool.axis) < 0.0) n = -n;
  if (n.dot(tool.axis) < tool.cone_cosine - kConeCosineSlack) return false;
  // The body edge must face the tool: n against the outward normal of one of its faces.
  if (!(n.dot(body.face_normals[0]) < 0.0) && !(n.dot(body.face_normals[1]) < 0.0)) return false;
  *flush_node = -1;
  for (int i = 0; i < 2; ++i)  // face i spans from the edge away from the other face's normal
    if (n.dot(tool.face_normals[i]) > kFlushCosine)
      *flush_node = body.nodes[d_body.dot(tool.face_normals[1 - i]) < 0.0 ? 1 : 0];
  contact->p_tool_W_m = closest.point1;
  contact->p_body_W_m = closest.point2;
  contact->n_W = n;
  contact->gap_m = (closest.point2 - closest.point1).dot(n);
  contact->SetBodyNodes({body.nodes[0], body.nodes[1]}, {1.0 - closest.t, closest.t});
  return true;
}

}  // namespace

void CollisionDetector::MakeEdgeTopology() {
  // Body: each triangle side keyed by its sorted end nodes; equal keys are one edge.
  const Eigen::Index num_triangles = surface_triangles_.cols();
  std::vector<std::array<int, 4>> sides;  // (low node, high node, triangle, side)
  sides.reserve(3 * num_triangles);
  for (Eigen::Index f = 0; f < num_triangles; ++f)
    for (int k = 0; k < 3; ++k) {
      const int i = surface_triangles_(k, f), j = surface_triangles_((k + 1) % 3, f);
      sides.push_back({std::min(i, j), std::max(i, j), static_cast<int>(f), k});
    }
  std::sort(sides.begin(), sides.end());
  triangle_edges_.resize(3, num_triangles);
  std::vector<std::array<int, 4>> edges;  // (low node, high node, triangle, triangle or −1)
  for (const std::array<int, 4>& side : sides) {
    if (edges.empty() || edges.back()[0] != side[0] || edges.back()[1] != side[1])
      edges.push_back({side[0], side[1], side[2], -1});
    else if (edges.back()[3] < 0)  // a third triangle on a non-manifold edge is not recorded
      edges.back()[3] = side[2];
    triangle_edges_(side[3], side[2]) = static_cast<int>(edges.size()) - 1;
  }
  body_edge_nodes_.resize(2, static_cast<Eigen::Index>(edges.size()));
  body_edge_triangles_.resize(2, static_cast<Eigen::Index>(edges.size()));
  for (size_t e = 0; e < edges.size(); ++e) {
    body_edge_nodes_.col(e) << edges[e][0], edges[e][1];
    body_edge_triangles_.col(e) << edges[e][2], edges[e][3];
  }
  edge_visited_.assign(edges.size(), 0);

  // Tool: the convex, non-flat feature edges with their normal cones.
  Matrix3Xd face_normals;
  std::vector<char> convex;
  CalcToolEdgeFaceNormals(tool_distance_.shape(), tool_features_, &face_normals, &convex);
  const Eigen::Index num_features = tool_features_.edges.cols();
  tool_edges_.resize(2, num_features);
  tool_edge_normals_T_.resize(3, 3 * num_features);
  tool_edge_cone_cosines_.resize(num_features);
  Eigen::Index kept = 0;
  for (Eigen::Index e = 0; e < num_features; ++e) {
    Vector3d axis;
    double cosine;
    if (!convex[e] ||
        !MakeEdgeCone(face_normals.col(2 * e), face_normals.col(2 * e + 1), &axis, &cosine))
      continue;
    tool_edges_.col(kept) = tool_features_.edges.col(e);
    tool_edge_normals_T_.col(3 * kept) = axis;
    tool_edge_normals_T_.middleCols<2>(3 * kept + 1) = face_normals.middleCols<2>(2 * e);
    tool_edge_cone_cosines_[kept++] = cosine;
  }
  tool_edges_.conservativeResize(2, kept);
  tool_edge_normals_T_.conservativeResize(3, 3 * kept);
  tool_edge_cone_cosines_.conservativeResize(kept);
  tool_edge_normals_W_.resize(3, 3 * kept);
  tool_vertices_W_m_.resize(3, tool_features_.vertices_T_m.cols());
  tool_edge_midpoints_W_m_.resize(3, kept);
  tool_edge_half_lengths_m_.resize(kept);
  Matrix3Xd midpoints_T_m(3, kept);
  for (Eigen::Index j = 0; j < kept; ++j) {
    const Vector3d p = tool_features_.vertices_T_m.col(tool_edges_(0, j));
    const Vector3d q = tool_features_.vertices_T_m.col(tool_edges_(1, j));
    tool_edge_half_lengths_m_[j] = 0.5 * (q - p).norm();
    midpoints_T_m.col(j) = 0.5 * (p + q);
  }
  MakeRunSpheres(midpoints_T_m, tool_edge_half_lengths_m_, &tool_edge_run_centers_T_m_,
                 &tool_edge_run_radii_m_);
  tool_edge_run_centers_W_m_.resize(3, tool_edge_run_centers_T_m_.cols());
}

void CollisionDetector::AddEdgeContacts(const Eigen::VectorXd& x_m, const Eigen::Isometry3d& X_WT,
                                        std::vector<Contact>* contacts) {
  const Eigen::Index num_tool_edges = tool_edges_.cols();
  if (num_tool_edges == 0 || candidate_triangles_.empty()) return;
  for (Eigen::Index i = 0; i < tool_vertices_W_m_.cols(); ++i)
    tool_vertices_W_m_.col(i) = X_WT * Vector3d(tool_features_.vertices_T_m.col(i));
  tool_edge_normals_W_.noalias() = X_WT.linear() * tool_edge_normals_T_;
  for (Eigen::Index j = 0; j < num_tool_edges; ++j)
    tool_edge_midpoints_W_m_.col(j) = 0.5 * (tool_vertices_W_m_.col(tool_edges_(0, j)) +
                                             tool_vertices_W_m_.col(tool_edges_(1, j)));
  for (Eigen::Index g = 0; g < tool_edge_run_centers_T_m_.cols(); ++g)
    tool_edge_run_centers_W_m_.col(g) = X_WT * Vector3d(tool_edge_run_centers_T_m_.col(g));
  const double threshold_m = statistics_.threshold_m;
  // Pairs whose bounding spheres are farther apart than this cannot make a contact.
  const double reach_m = std::max(threshold_m, options_.max_feature_penetration_m);
  BodyEdge body;
  ToolEdge tool;
  Contact contact;
  int flush_node;
  for (int f : candidate_triangles_)
    for (int k = 0; k < 3; ++k) {
      const int e = triangle_edges_(k, f);
      if (edge_visited_[e] == frame_stamp_) continue;
      edge_visited_[e] = frame_stamp_;
      for (int end = 0; end < 2; ++end) {
        body.nodes[end] = body_edge_nodes_(end, e);
        const int t = body_edge_triangles_(end, e);
        body.face_normals[end].setZero();
        if (t < 0) continue;
        const Vector3d a = x_m.segment<3>(3 * surface_triangles_(0, t));
        body.face_normals[end] = (x_m.segment<3>(3 * surface_triangles_(1, t)) - a)
                                     .cross(x_m.segment<3>(3 * surface_triangles_(2, t)) - a);
      }
      body.a = x_m.segment<3>(3 * body.nodes[0]);
      body.b = x_m.segment<3>(3 * body.nodes[1]);
      const Vector3d body_midpoint_W_m = 0.5 * (body.a + body.b);
      const double body_reach_m = 0.5 * (body.b - body.a).norm() + reach_m;
      // A run's sphere first, then its edges': block_press's ~440 body edges a frame each met the
      // 64 rim edges' spheres one by one, the far rim's too (0.110 → 0.104 ms, the same pairs).
      for (Eigen::Index j = 0; j < num_tool_edges; ++j) {
        if (j % kToolRun == 0) {
          const Eigen::Index g = j / kToolRun;
          const double run_apart_m = tool_edge_run_radii_m_[g] + body_reach_m;
          if ((tool_edge_run_centers_W_m_.col(g) - body_midpoint_W_m).squaredNorm() >
              run_apart_m * run_apart_m) {
            j += kToolRun - 1;  // past the run
            continue;
          }
        }
        const double apart_m = tool_edge_half_lengths_m_[j] + body_reach_m;
        if ((tool_edge_midpoints_W_m_.col(j) - body_midpoint_W_m).squaredNorm() > apart_m * apart_m)
          continue;
        tool.p = tool_vertices_W_m_.col(tool_edges_(0, j));
        tool.q = tool_vertices_W_m_.col(tool_edges_(1, j));
        tool.axis = tool_edge_normals_W_.col(3 * j);
        tool.face_normals = {tool_edge_normals_W_.col(3 * j + 1),
                             tool_edge_normals_W_.col(3 * j + 2)};
        tool.cone_cosine = tool_edge_cone_cosines_[j];
        if (!CalcEdgeContact(tool, body, &contact, &flush_node)) continue;
        if (contact.gap_m > threshold_m || contact.gap_m < -options_.max_feature_penetration_m)
          continue;
        if (flush_node >= 0 && node_in_contact_[flush_node] == frame_stamp_) continue;
        contacts->push_back(contact);
      }
    }
}

}  // namespace hapsim::contact
