#include "fem/tet_mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "fem/quadratic_tet.h"

namespace hapsim::fem {

double CalcSignedVolume(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                        const Eigen::Vector3d& p2, const Eigen::Vector3d& p3) {
  return (p1 - p0).dot((p2 - p0).cross(p3 - p0)) / 6.0;
}

double CalcSignedVolume(const Matrix3Xd& p_m, const Eigen::Vector4i& tet) {
  return CalcSignedVolume(p_m.col(tet[0]), p_m.col(tet[1]), p_m.col(tet[2]), p_m.col(tet[3]));
}

double CalcTetQuality(const Matrix3Xd& p_m, const Eigen::Vector4i& tet) {
  double sum_sq_m2 = 0.0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) sum_sq_m2 += (p_m.col(tet[a]) - p_m.col(tet[b])).squaredNorm();
  const double rms_edge_m = std::sqrt(sum_sq_m2 / 6.0);
  if (!(rms_edge_m > 0.0)) return 0.0;
  // A regular tet of edge ℓ has V = ℓ³ / (6√2), hence the normalisation.
  return 6.0 * std::sqrt(2.0) * CalcSignedVolume(p_m, tet) / (rms_edge_m * rms_edge_m * rms_edge_m);
}

TetMeshQuality CalcTetMeshQuality(const TetMesh& mesh) {
  TetMeshQuality quality;
  quality.num_tets = static_cast<int>(mesh.tets.cols());
  quality.min_dihedral_deg = 180.0;
  quality.max_dihedral_deg = 0.0;
  for (int e = 0; e < mesh.tets.cols(); ++e) {
    const Eigen::Vector4i tet = mesh.tets.col(e);
    quality.volume_m3 += CalcSignedVolume(mesh.rest_positions_m, tet);
    // Outward normals of the faces opposite each vertex; the dihedral angle at the edge shared by
    // the faces opposite a and b is π less the angle between their outward normals.
    std::array<Eigen::Vector3d, 4> normal;
    for (int a = 0; a < 4; ++a) {
      const Eigen::Vector3d p0 = mesh.rest_positions_m.col(tet[(a + 1) % 4]);
      const Eigen::Vector3d p1 = mesh.rest_positions_m.col(tet[(a + 2) % 4]);
      const Eigen::Vector3d p2 = mesh.rest_positions_m.col(tet[(a + 3) % 4]);
      Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
      if (n.dot(mesh.rest_positions_m.col(tet[a]) - p0) > 0.0) n = -n;  // away from vertex a
      normal[a] = n.normalized();
    }
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        const double cos_normals = std::clamp(normal[a].dot(normal[b]), -1.0, 1.0);
        const double dihedral_deg = 180.0 - std::acos(cos_normals) * 180.0 / M_PI;
        quality.min_dihedral_deg = std::min(quality.min_dihedral_deg, dihedral_deg);
        quality.max_dihedral_deg = std::max(quality.max_dihedral_deg, dihedral_deg);
      }
  }
  return quality;
}

namespace {

// The edge between nodes a and b, either way round, as a hash key.
std::uint64_t UndirectedEdgeKey(int a, int b) {
  return (static_cast<std::uint64_t>(std::min(a, b)) << 32) |
         static_cast<std::uint32_t>(std::max(a, b));
}

// A quadratic tet's edge nodes: indices in range, distinct, and a mapping that does not fold
// (FindQuadraticTetProblem: an edge node far off its edge's midpoint).
std::optional<std::string> FindEdgeNodeProblem(const TetMesh& mesh, int t) {
  if (!mesh.is_quadratic()) return std::nullopt;
  const std::string tet = "tet " + std::to_string(t);
  P2Nodes X;
  for (int a = 0; a < kP2Nodes; ++a) {
    const int node = mesh.node(a, t);
    if (node < 0 || node >= mesh.num_nodes())
      return tet + " refers to node " + std::to_string(node) + ", but the mesh has " +
             std::to_string(mesh.num_nodes()) + " nodes";
    for (int b = 0; b < a; ++b)
      if (mesh.node(b, t) == node) return tet + " uses node " + std::to_string(node) + " twice";
    X.col(a) = mesh.rest_positions_m.col(node);
  }
  if (auto problem = FindQuadraticTetProblem(X)) return tet + ": " + *problem;
  return std::nullopt;
}

// A quadratic mesh whose tets agree on their edge nodes: an edge has one node, shared by every
// tet around it, which is no tet's corner and no other edge's node. Otherwise the body is cracked
// along that edge (each tet would bend it its own way).
std::optional<std::string> FindSharedEdgeProblem(const TetMesh& mesh, int* bad_tet) {
  std::vector<std::uint8_t> is_corner(static_cast<size_t>(mesh.num_nodes()), 0);
  for (int t = 0; t < mesh.num_tets(); ++t)
    for (int a = 0; a < 4; ++a) is_corner[static_cast<size_t>(mesh.tets(a, t))] = 1;
  std::unordered_map<std::uint64_t, int> node_of_edge;
  std::unordered_map<int, std::uint64_t> edge_of_node;
  for (int t = 0; t < mesh.num_tets(); ++t)
    for (int k = 0; k < 6; ++k) {
      if (bad_tet) *bad_tet = t;
      const int a = mesh.tets(kP2EdgeCorners[k][0], t), b = mesh.tets(kP2EdgeCorners[k][1], t);
      const std::uint64_t key = UndirectedEdgeKey(a, b);
      const int node = mesh.edge_nodes(k, t);
      const std::string edge = "edge (" + std::to_string(a) + ", " + std::to_string(b) + ")";
      if (is_corner[static_cast<size_t>(node)])
        return "tet " + std::to_string(t) + " puts node " + std::to_string(node) + " on its " +
               edge + ", but it is another tet's corner";
      const auto [at_edge, new_edge] = node_of_edge.emplace(key, node);
      if (!new_edge && at_edge->second != node)
        return "tet " + std::to_string(t) + " puts node " + std::to_string(node) + " on " + edge +
               ", which another tet gives node " + std::to_string(at_edge->second) +
               ": the mesh is cracked along it";
      const auto [at_node, new_node] = edge_of_node.emplace(node, key);
      if (!new_node && at_node->second != key)
        return "tet " + std::to_string(t) + " puts node " + std::to_string(node) + " on " + edge +
               ", but another tet has it on another edge";
    }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> FindRestMeshProblem(const TetMesh& mesh, int* bad_tet) {
  const int num_nodes = mesh.num_nodes();
  if (!mesh.rest_positions_m.allFinite()) return std::string("a node position is not finite");
  if (mesh.is_quadratic() && mesh.edge_nodes.cols() != mesh.tets.cols())
    return "the mesh has " + std::to_string(mesh.tets.cols()) + " tets but edge nodes for " +
           std::to_string(mesh.edge_nodes.cols());
  for (int t = 0; t < mesh.num_tets(); ++t) {
    if (bad_tet) *bad_tet = t;
    const Eigen::Vector4i tet = mesh.tets.col(t);
    for (int a = 0; a < 4; ++a) {
      if (tet[a] < 0 || tet[a] >= num_nodes)
        return "tet " + std::to_string(t) + " refers to node " + std::to_string(tet[a]) +
               ", but the mesh has " + std::to_string(num_nodes) + " nodes";
      for (int b = a + 1; b < 4; ++b)
        if (tet[a] == tet[b])
          return "tet " + std::to_string(t) + " uses node " + std::to_string(tet[a]) + " twice";
    }
    const double quality = CalcTetQuality(mesh.rest_positions_m, tet);
    if (!std::isfinite(quality))  // finite coordinates whose products overflow
      return "tet " + std::to_string(t) + " has a volume or shape that is not a finite number";
    if (quality <= -kDegenerateTetQuality)
      return "tet " + std::to_string(t) + " is inverted (negative volume " +
             std::to_string(CalcSignedVolume(mesh.rest_positions_m, tet)) + " m^3)";
    if (quality <= kDegenerateTetQuality)
      return "tet " + std::to_string(t) + " is degenerate (zero volume)";
    if (auto problem = FindEdgeNodeProblem(mesh, t)) return problem;
  }
  if (mesh.is_quadratic())
    if (auto problem = FindSharedEdgeProblem(mesh, bad_tet)) return problem;
  if (bad_tet) *bad_tet = -1;
  return std::nullopt;
}

namespace {

// For a positively oriented tet (a,b,c,d) these four faces have outward normals.
constexpr int kOutwardFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

// Face `face` (kOutwardFaces) of quadratic tet t as its four sub-triangles, from `column` on:
// (o0 e0 e2) (e0 o1 e1) (e2 e1 o2) (e0 e1 e2), with o its corners as oriented and e_k the edge
// node between o_k and o_(k+1) (contact/quadratic_surface.h reads this layout).
void WriteSubTriangles(const TetMesh& mesh, int t, int face, Eigen::Index column,
                       Matrix3Xi* surface) {
  const int* f = kOutwardFaces[face];
  int o[3], e[3];
  for (int k = 0; k < 3; ++k) {
    o[k] = mesh.tets(f[k], t);
    e[k] = mesh.edge_nodes(FindP2Edge(f[k], f[(k + 1) % 3]), t);
  }
  surface->col(column) << o[0], e[0], e[2];
  surface->col(column + 1) << e[0], o[1], e[1];
  surface->col(column + 2) << e[2], e[1], o[2];
  surface->col(column + 3) << e[0], e[1], e[2];
}

}  // namespace

Matrix3Xi ExtractBoundarySurface(const TetMesh& mesh) {
  struct FaceRecord {
    int tet = -1, face = -1;  // a tet holding it and its face there (kOutwardFaces)
    int count = 0;
  };
  struct KeyHash {
    size_t operator()(const std::array<int, 3>& k) const {
      return (static_cast<size_t>(k[0]) * 73856093u) ^ (static_cast<size_t>(k[1]) * 19349663u) ^
             (static_cast<size_t>(k[2]) * 83492791u);
    }
  };
  std::unordered_map<std::array<int, 3>, FaceRecord, KeyHash> faces;
  faces.reserve(static_cast<size_t>(mesh.num_tets()) * 4);
  for (int t = 0; t < mesh.num_tets(); ++t) {
    for (int face = 0; face < 4; ++face) {
      const int* f = kOutwardFaces[face];
      std::array<int, 3> key = {mesh.tets(f[0], t), mesh.tets(f[1], t), mesh.tets(f[2], t)};
      std::sort(key.begin(), key.end());
      FaceRecord& record = faces[key];
      record.tet = t;
      record.face = face;
      ++record.count;
    }
  }
  // Deterministic output order: sort the boundary faces by their sorted key.
  std::vector<std::array<int, 3>> keys;
  for (const auto& [key, record] : faces)
    if (record.count == 1) keys.push_back(key);
  std::sort(keys.begin(), keys.end());
  const int per_face = mesh.is_quadratic() ? 4 : 1;
  Matrix3Xi surface(3, per_face * static_cast<Eigen::Index>(keys.size()));
  for (size_t i = 0; i < keys.size(); ++i) {
    const FaceRecord& record = faces[keys[i]];
    const Eigen::Index column = per_face * static_cast<Eigen::Index>(i);
    if (mesh.is_quadratic()) {
      WriteSubTriangles(mesh, record.tet, record.face, column, &surface);
    } else {
      const int* f = kOutwardFaces[record.face];
      surface.col(column) << mesh.tets(f[0], record.tet), mesh.tets(f[1], record.tet),
          mesh.tets(f[2], record.tet);
    }
  }
  return surface;
}

TetMesh MakeQuadraticMesh(const TetMesh& linear) {
  if (linear.is_quadratic()) return linear;
  TetMesh mesh;
  mesh.tets = linear.tets;
  mesh.edge_nodes.resize(6, linear.num_tets());
  std::unordered_map<std::uint64_t, int> node_of_edge;
  node_of_edge.reserve(static_cast<size_t>(linear.num_tets()) * 2);
  std::vector<Eigen::Vector3d> added;
  const int num_corners = linear.num_nodes();
  for (int t = 0; t < linear.num_tets(); ++t)
    for (int k = 0; k < 6; ++k) {
      const int a = linear.tets(kP2EdgeCorners[k][0], t), b = linear.tets(kP2EdgeCorners[k][1], t);
      const std::uint64_t key = UndirectedEdgeKey(a, b);
      const auto [it, is_new] =
          node_of_edge.emplace(key, num_corners + static_cast<int>(added.size()));
      if (is_new)
        added.push_back(0.5 * (linear.rest_positions_m.col(a) + linear.rest_positions_m.col(b)));
      mesh.edge_nodes(k, t) = it->second;
    }
  mesh.rest_positions_m.resize(3, num_corners + static_cast<Eigen::Index>(added.size()));
  mesh.rest_positions_m.leftCols(num_corners) = linear.rest_positions_m;
  for (size_t i = 0; i < added.size(); ++i)
    mesh.rest_positions_m.col(num_corners + static_cast<Eigen::Index>(i)) = added[i];
  return mesh;
}

}  // namespace hapsim::fem
