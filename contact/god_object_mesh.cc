// The god-object's meshes (contact/god_object.h): topology, normals, edge widths, the AABB
// tree over the widened, moved-out triangles, and the first-crossing query along a path.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "contact/god_object.h"
#include "contact/tool_distance.h"

namespace hapsim::contact {

using Eigen::Vector3d;

namespace {

// Edges are widened by r tan(θ/2), θ the convex exterior dihedral angle, at most this times r
// (θ ≈ 152°): sharper edges leave a gap between the moved-out faces (header comment).
constexpr double kMaxWideningFactor = 4.0;
constexpr int kLeafSize = 4;
// Depth-first stack of the tree query: a median split halves the triangles at every level, so
// the depth is about log2(F / kLeafSize) (< 30 for a billion triangles), the stack at most that.
constexpr int kMaxStack = 64;

// Whether p0 + t (p1 − p0), t ∈ [0, t_max], meets the box (slab test).
bool SegmentHitsBox(const Eigen::AlignedBox3d& box, const Vector3d& p0, const Vector3d& d,
                    double t_max) {
  double t0 = 0.0, t1 = t_max;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d(i)) < 1e-300) {
      if (p0(i) < box.min()(i) || p0(i) > box.max()(i)) return false;
      continue;
    }
    const double inv = 1.0 / d(i);
    double ta = (box.min()(i) - p0(i)) * inv;
    double tb = (box.max()(i) - p0(i)) * inv;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

// Coordinates (u, v, h) of p relative to triangle (a, b, c) with unit normal n:
// p = a + u (b − a) + v (c − a) + h n.
Vector3d CalcTriangleCoordinates(const Vector3d& p, const Vector3d& a, const Vector3d& b,
                                 const Vector3d& c, const Vector3d& n) {
  const Vector3d e1 = b - a, e2 = c - a, d = p - a;
  const double g11 = e1.dot(e1), g12 = e1.dot(e2), g22 = e2.dot(e2);
  const double det = g11 * g22 - g12 * g12;
  const double b1 = d.dot(e1), b2 = d.dot(e2);
  return Vector3d((g22 * b1 - g12 * b2) / det, (g11 * b2 - g12 * b1) / det, n.dot(d));
}

}  // namespace

int GodObject::AddMesh(const TriangleMesh& mesh_O, const Eigen::Isometry3d& X_WO) {
  const int num_vertices = static_cast<int>(mesh_O.vertices_m.cols());
  const int num_triangles = static_cast<int>(mesh_O.triangles.cols());
  if (num_vertices == 0 || num_triangles == 0)
    throw std::invalid_argument("GodObject::AddMesh: empty mesh");
  if (mesh_O.triangles.minCoeff() < 0 || mesh_O.triangles.maxCoeff() >= num_vertices)
    throw std::invalid_argument("GodObject::AddMesh: triangle vertex index out of range");
  Mesh mesh;
  mesh.vertices_O_m = mesh_O.vertices_m;
  mesh.triangles = mesh_O.triangles;
  mesh.X_WO = mesh.X_WO_last = X_WO;
  // Neighbours across each edge: sort the edges by their vertex pair; a pair shared by exactly
  // two triangles is an interior edge, anything else a boundary.
  struct Edge {
    int lo, hi, f, k;
  };
  std::vector<Edge> edges;
  edges.reserve(3 * num_triangles);
  for (int f = 0; f < num_triangles; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.triangles(k, f), b = mesh.triangles((k + 1) % 3, f);
      edges.push_back({std::min(a, b), std::max(a, b), f, k});
    }
  }
  std::sort(edges.begin(), edges.end(),
            [](const Edge& x, const Edge& y) { return x.lo != y.lo ? x.lo < y.lo : x.hi < y.hi; });
  mesh.neighbours.setConstant(3, num_triangles, -1);
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi) ++j;
    if (j - i == 2) {
      mesh.neighbours(edges[i].k, edges[i].f) = edges[i + 1].f;
      mesh.neighbours(edges[i + 1].k, edges[i + 1].f) = edges[i].f;
    }
    i = j;
  }
  mesh.face_normals_O.resize(3, num_triangles);
  mesh.offsets_m.resize(num_triangles);
  mesh.edge_widths_m.resize(3, num_triangles);
  mesh.vertex_normals_O.resize(3, num_vertices);
  CalcGeometry(&mesh);

  std::vector<Eigen::AlignedBox3d> boxes(num_triangles);
  std::vector<Vector3d> centres(num_triangles);
  for (int f = 0; f < num_triangles; ++f) {
    boxes[f] = CalcTriangleBox(mesh, f);
    centres[f] = boxes[f].center();
  }
  mesh.order.resize(num_triangles);
  for (int f = 0; f < num_triangles; ++f) mesh.order[f] = f;
  mesh.nodes.reserve(2 * (num_triangles / kLeafSize + 1));
  BuildNode(&mesh, 0, num_triangles, &boxes, &centres);
  meshes_.push_back(std::move(mesh));
  return static_cast<int>(meshes_.size()) - 1;
}

int GodObject::BuildNode(Mesh* mesh, int first, int count, std::vector<Eigen::AlignedBox3d>* boxes,
                         std::vector<Vector3d>* centres) {
  const int index = static_cast<int>(mesh->nodes.size());
  mesh->nodes.emplace_back();
  Eigen::AlignedBox3d box, centre_box;
  for (int i = first; i < first + count; ++i) {
    box.extend((*boxes)[mesh->order[i]]);
    centre_box.extend((*centres)[mesh->order[i]]);
  }
  mesh->nodes[index].box = box;
  if (count <= kLeafSize) {
    mesh->nodes[index].first = first;
    mesh->nodes[index].count = count;
    return index;
  }
  // Median split along the longest axis of the triangle centres.
  int axis;
  centre_box.sizes().maxCoeff(&axis);
  const int half = count / 2;
  std::nth_element(mesh->order.begin() + first, mesh->order.begin() + first + half,
                   mesh->order.begin() + first + count,
                   [&](int a, int b) { return (*centres)[a](axis) < (*centres)[b](axis); });
  BuildNode(mesh, first, half, boxes, centres);
  const int right = BuildNode(mesh, first + half, count - half, boxes, centres);
  mesh->nodes[index].right = right;
  return index;
}

void GodObject::CalcGeometry(Mesh* mesh) const {
  const double r = params_.proxy_radius_m;
  const double epsilon = params_.surface_epsilon_m;
  const auto& V = mesh->vertices_O_m;
  const auto& T = mesh->triangles;
  const int num_triangles = static_cast<int>(T.cols());
  mesh->vertex_normals_O.setZero();
  for (int f = 0; f < num_triangles; ++f) {
    const Vector3d a = V.col(T(0, f)), b = V.col(T(1, f)), c = V.col(T(2, f));
    const Vector3d cross = (b - a).cross(c - a);
    const double scale = std::max({(b - a).squaredNorm(), (c - a).squaredNorm(), 1e-300});
    // Degenerate: the cross product vanishes against the edge lengths (relative 1e-12).
    const bool degenerate = cross.norm() <= 1e-12 * scale;
    const Vector3d n = degenerate ? Vector3d::Zero() : Vector3d(cross.normalized());
    mesh->face_normals_O.col(f) = n;
    mesh->offsets_m(f) = n.dot(a) + r;
    if (degenerate) continue;
    for (int k = 0; k < 3; ++k) {  // angle-weighted vertex normals
      const Vector3d p = V.col(T(k, f));
      const Vector3d e1 = V.col(T((k + 1) % 3, f)) - p, e2 = V.col(T((k + 2) % 3, f)) - p;
      const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
      mesh->vertex_normals_O.col(T(k, f)) += angle * n;
    }
  }
  for (int v = 0; v < mesh->vertex_normals_O.cols(); ++v) {
    const double norm = mesh->vertex_normals_O.col(v).norm();
    if (norm > 0.0) mesh->vertex_normals_O.col(v) /= norm;
  }
  for (int f = 0; f < num_triangles; ++f) {
    const Vector3d n = mesh->face_normals_O.col(f);
    for (int k = 0; k < 3; ++k) {
      const int g = mesh->neighbours(k, f);
      double factor = 1.0;  // boundary edge, or next to a degenerate triangle: as a 90° edge
      if (g >= 0 && mesh->face_normals_O.col(g).squaredNorm() > 0.0) {
        const Vector3d m = mesh->face_normals_O.col(g);
        // The neighbour's vertex off the shared edge: below this face's plane for a convex edge.
        const int a = T(k, f), b = T((k + 1) % 3, f);
        int w = T(0, g);
        for (int i = 0; i < 3; ++i) {
          if (T(i, g) != a && T(i, g) != b) w = T(i, g);
        }
        const bool convex = n.dot(V.col(w) - V.col(a)) < 0.0;
        const double denominator = 1.0 + n.dot(m);  // tan(θ/2) = sin θ / (1 + cos θ)
        factor = !convex ? 0.0
                 : denominator * kMaxWideningFactor > n.cross(m).norm()
                     ? n.cross(m).norm() / denominator
                     : kMaxWideningFactor;
      }
      mesh->edge_widths_m(k, f) = r * factor + epsilon;
    }
  }
}

Eigen::AlignedBox3d GodObject::CalcTriangleBox(const Mesh& mesh, int f) const {
  const Vector3d shift = params_.proxy_radius_m * mesh.face_normals_O.col(f);
  Eigen::AlignedBox3d box;
  for (int k = 0; k < 3; ++k) {
    const Vector3d p = mesh.vertices_O_m.col(mesh.triangles(k, f));
    box.extend(p);
    box.extend(Vector3d(p + shift));
  }
  // Room for the widened corners: where edges widened by w1, w2 meet at an interior angle β the
  // corner moves by √(w1² + w2² + 2 w1 w2 cos β) / sin β, at most 4 max(w) (β ≳ 29°); sliver
  // corners are cut by the box, which CalcTriangleCrossing also applies (the tree and the brute
  // force agree).
  const auto& w = mesh.edge_widths_m;
  const double w_max = w.col(f).maxCoeff();
  double grow = w_max;
  for (int k = 0; k < 3; ++k) {
    const Vector3d p = mesh.vertices_O_m.col(mesh.triangles(k, f));
    const Vector3d e1 = mesh.vertices_O_m.col(mesh.triangles((k + 1) % 3, f)) - p;
    const Vector3d e2 = mesh.vertices_O_m.col(mesh.triangles((k + 2) % 3, f)) - p;
    const double cos_b = e1.dot(e2), sin_b = e1.cross(e2).norm();  // times |e1| |e2|
    const double w1 = w(k, f), w2 = w((k + 2) % 3, f);  // the edges from p to k+1 and k+2
    const double num = (w1 * w1 + w2 * w2) * e1.squaredNorm() * e2.squaredNorm() +
                       2 * w1 * w2 * cos_b * e1.norm() * e2.norm();
    const double cap = kMaxWideningFactor * w_max;
    grow = std::max(grow, num < cap * cap * sin_b * sin_b ? std::sqrt(num) / sin_b : cap);
  }
  box.min().array() -= grow;
  box.max().array() += grow;
  return box;
}

void GodObject::RefitTree(Mesh* mesh) const {
  for (int i = static_cast<int>(mesh->nodes.size()) - 1; i >= 0; --i) {
    Node& node = mesh->nodes[i];
    node.box.setEmpty();
    if (node.count > 0) {
      for (int j = node.first; j < node.first + node.count; ++j)
        node.box.extend(CalcTriangleBox(*mesh, mesh->order[j]));
    } else {
      node.box.extend(mesh->nodes[i + 1].box);
      node.box.extend(mesh->nodes[node.right].box);
    }
  }
}

void GodObject::SetMeshPose(int id, const Eigen::Isometry3d& X_WO) {
  if (id < 0 || id >= num_meshes())
    throw std::invalid_argument("GodObject::SetMeshPose: bad mesh id " + std::to_string(id));
  meshes_[id].X_WO = X_WO;
}

void GodObject::SetMeshVertices(int id, const Matrix3Xd& vertices_O_m) {
  if (id < 0 || id >= num_meshes())
    throw std::invalid_argument("GodObject::SetMeshVertices: bad mesh id " + std::to_string(id));
  Mesh& mesh = meshes_[id];
  if (vertices_O_m.cols() != mesh.vertices_O_m.cols())
    throw std::invalid_argument("GodObject::SetMeshVertices: vertex count differs from the mesh");
  // A god-object resting on this mesh is carried along with its first triangle: the same
  // coordinates (u, v, h) on the moved triangle; so is the stiction point.
  const bool carry = num_active_ > 0 && active_[0].mesh == id &&
                     mesh.face_normals_O.col(active_[0].triangle).squaredNorm() > 0.0;
  const int f = carry ? active_[0].triangle : 0;
  const double max_move_m = (vertices_O_m - mesh.vertices_O_m).colwise().norm().maxCoeff();
  const auto corner = [&](int k) { return mesh.vertices_O_m.col(mesh.triangles(k, f)); };
  Vector3d god_uvh = Vector3d::Zero(), proxy_uvh = Vector3d::Zero();
  if (carry) {
    const Eigen::Isometry3d X_OW = mesh.X_WO_last.inverse(Eigen::Isometry);
    const Vector3d n = mesh.face_normals_O.col(f);
    god_uvh = CalcTriangleCoordinates(X_OW * god_object_W_m_, corner(0), corner(1), corner(2), n);
    proxy_uvh = CalcTriangleCoordinates(X_OW * proxy_W_m_, corner(0), corner(1), corner(2), n);
  }
  mesh.vertices_O_m = vertices_O_m;
  CalcGeometry(&mesh);
  RefitTree(&mesh);
  if (carry && mesh.face_normals_O.col(f).squaredNorm() > 0.0) {
    const Vector3d n = mesh.face_normals_O.col(f);
    const auto place = [&](const Vector3d& uvh) {
      return mesh.X_WO_last * (corner(0) + uvh(0) * (corner(1) - corner(0)) +
                               uvh(1) * (corner(2) - corner(0)) + uvh(2) * n);
    };
    const double lift_m = 2.0 * params_.proxy_radius_m + max_move_m + params_.surface_epsilon_m;
    god_object_W_m_ = Reseat(id, f, place(god_uvh), lift_m);
    proxy_W_m_ = Reseat(id, f, place(proxy_uvh), lift_m);
  }
}

Vector3d GodObject::Reseat(int id, int f, const Vector3d& p_W_m, double lift_m) const {
  const Mesh& mesh = meshes_[id];
  const Eigen::Isometry3d X_OW = mesh.X_WO_last.inverse(Eigen::Isometry);
  const Vector3d p_O = X_OW * p_W_m;
  const Vector3d top_O = p_O + lift_m * mesh.face_normals_O.col(f);
  const Crossing crossing = CalcFirstCrossing(id, top_O, p_O);
  if (crossing.triangle < 0) return p_W_m;
  const Vector3d met_O = top_O + crossing.t * (p_O - top_O) +
                         params_.surface_epsilon_m * mesh.face_normals_O.col(crossing.triangle);
  return mesh.X_WO_last * met_O;
}

double GodObject::CalcTriangleCrossing(const Mesh& mesh, int f, const Vector3d& p0_O,
                                       const Vector3d& p1_O) const {
  constexpr double kNone = 2.0;
  const Vector3d n = mesh.face_normals_O.col(f);
  if (n.squaredNorm() == 0.0) return kNone;
  const double s0 = n.dot(p0_O) - mesh.offsets_m(f);
  const double s1 = n.dot(p1_O) - mesh.offsets_m(f);
  if (!(s0 >= 0.0 && s1 < 0.0)) return kNone;  // only from the front
  const double t = s0 / (s0 - s1);
  const Vector3d q = p0_O + t * (p1_O - p0_O);
  for (int k = 0; k < 3; ++k) {
    const Vector3d a = mesh.vertices_O_m.col(mesh.triangles(k, f));
    const Vector3d edge = mesh.vertices_O_m.col(mesh.triangles((k + 1) % 3, f)) - a;
    const Vector3d out = edge.cross(n);  // in-plane, away from the triangle (CCW about n)
    if (out.dot(q - a) > mesh.edge_widths_m(k, f) * out.norm()) return kNone;
  }
  if (!CalcTriangleBox(mesh, f).contains(q)) return kNone;
  return t;
}

GodObject::Crossing GodObject::CalcFirstCrossing(int id, const Vector3d& p0_O_m,
                                                 const Vector3d& p1_O_m,
                                                 const Exclusions& exclude) const {
  const Mesh& mesh = meshes_.at(id);
  const Vector3d d = p1_O_m - p0_O_m;
  Crossing best;
  int stack[kMaxStack];
  int size = 0;
  stack[size++] = 0;
  while (size > 0) {
    const Node& node = mesh.nodes[stack[--size]];
    if (!SegmentHitsBox(node.box, p0_O_m, d, best.t)) continue;
    if (node.count > 0) {
      for (int j = node.first; j < node.first + node.count; ++j) {
        const int f = mesh.order[j];
        if (f == exclude[0] || f == exclude[1] || f == exclude[2]) continue;
        const double t = CalcTriangleCrossing(mesh, f, p0_O_m, p1_O_m);
        if (t < best.t || (t == best.t && best.triangle >= 0 && f < best.triangle)) {
          best.t = t;
          best.triangle = f;
        }
      }
    } else {
      stack[size++] = node.right;
      stack[size++] = static_cast<int>(&node - mesh.nodes.data()) + 1;
    }
  }
  return best;
}

GodObject::Crossing GodObject::CalcFirstCrossingBruteForce(int id, const Vector3d& p0_O_m,
                                                           const Vector3d& p1_O_m,
                                                           const Exclusions& exclude) const {
  const Mesh& mesh = meshes_.at(id);
  Crossing best;
  for (int f = 0; f < mesh.triangles.cols(); ++f) {
    if (f == exclude[0] || f == exclude[1] || f == exclude[2]) continue;
    const double t = CalcTriangleCrossing(mesh, f, p0_O_m, p1_O_m);
    if (t < best.t) {
      best.t = t;
      best.triangle = f;
    }
  }
  return best;
}

}  // namespace hapsim::contact
