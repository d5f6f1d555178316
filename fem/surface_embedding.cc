#include "fem/surface_embedding.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "core/closest_points.h"
#include "fem/quadratic_tet.h"

namespace hapsim::fem {
namespace {

using Eigen::Vector3d;
using Eigen::Vector4d;

// Barycentric coordinates of p in tet t, inside or out: D λ = p − X0, D = [X1−X0, X2−X0, X3−X0],
// w = (1 − Σλ, λ). Σ_a w_a X_a = p exactly, whatever the sign of the weights.
Vector4d CalcBarycentric(const TetMesh& mesh, int t, const Vector3d& p_m) {
  const Matrix3Xd& X = mesh.rest_positions_m;
  const Vector3d x0 = X.col(mesh.tets(0, t));
  Eigen::Matrix3d D;
  for (int a = 1; a < 4; ++a) D.col(a - 1) = X.col(mesh.tets(a, t)) - x0;
  const Vector3d lambda = D.partialPivLu().solve(p_m - x0);
  return Vector4d(1.0 - lambda.sum(), lambda.x(), lambda.y(), lambda.z());
}

// Distance from p to the surface of tet t: the nearest of its four faces' closest points (for a
// point outside the tet, its distance to the tet).
double CalcDistanceToTet(const TetMesh& mesh, int t, const Vector3d& p_m) {
  static constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  const Matrix3Xd& X = mesh.rest_positions_m;
  double distance_m = std::numeric_limits<double>::infinity();
  for (const auto& face : kFaces) {
    const TrianglePoint q =
        CalcClosestPointOnTriangle(p_m, X.col(mesh.tets(face[0], t)), X.col(mesh.tets(face[1], t)),
                                   X.col(mesh.tets(face[2], t)));
    distance_m = std::min(distance_m, (q.point - p_m).norm());
  }
  return distance_m;
}

// A uniform grid over the mesh's box; each cell lists the tets whose bounding box meets it
// (compressed rows: the tets of cell c are tets_[first_[c] .. first_[c + 1])).
class TetGrid {
 public:
  // Cells about `edge_m` across, larger where the tets are spread thin (pieces far apart): at
  // most ~8 cells per tet, whatever the mesh's extent.
  TetGrid(const TetMesh& mesh, double edge_m) {
    Eigen::AlignedBox3d box;
    for (int n = 0; n < mesh.num_nodes(); ++n) box.extend(Vector3d(mesh.rest_positions_m.col(n)));
    origin_m_ = box.min();
    const Vector3d extent_m = (box.max() - box.min()).cwiseMax(edge_m);
    cell_m_ = std::max(edge_m, std::cbrt(extent_m.prod() / (8.0 * mesh.num_tets() + 1.0)));
    dims_ = ((extent_m / cell_m_).array().floor() + 1.0).cast<int>();
    std::vector<std::vector<int>> cells(static_cast<size_t>(dims_.cast<std::int64_t>().prod()));
    for (int t = 0; t < mesh.num_tets(); ++t) {
      Eigen::AlignedBox3d tet_box;
      for (int a = 0; a < 4; ++a)
        tet_box.extend(Vector3d(mesh.rest_positions_m.col(mesh.tets(a, t))));
      ForEachCell(tet_box, [&](int c) { cells[c].push_back(t); });
    }
    first_.push_back(0);
    for (const std::vector<int>& cell : cells) {
      tets_.insert(tets_.end(), cell.begin(), cell.end());
      first_.push_back(static_cast<int>(tets_.size()));
    }
  }

  // Calls f(cell) for every cell meeting `box` (clamped to the grid).
  template <typename F>
  void ForEachCell(const Eigen::AlignedBox3d& box, F&& f) const {
    const Eigen::Vector3i lo = CellOf(box.min()), hi = CellOf(box.max());
    for (int k = lo.z(); k <= hi.z(); ++k)
      for (int j = lo.y(); j <= hi.y(); ++j)
        for (int i = lo.x(); i <= hi.x(); ++i) f(i + dims_.x() * (j + dims_.y() * k));
  }
  template <typename F>
  void ForEachTet(int cell, F&& f) const {
    for (int e = first_[cell]; e < first_[cell + 1]; ++e) f(tets_[e]);
  }

 private:
  // Clamped in double before the cast: a point far off the grid stays a defined cell.
  Eigen::Vector3i CellOf(const Vector3d& p_m) const {
    const Eigen::Array3d cell = ((p_m - origin_m_) / cell_m_).array().floor();
    return cell.max(0.0).min((dims_ - Eigen::Vector3i::Ones()).cast<double>().array()).cast<int>();
  }

  double cell_m_;
  Vector3d origin_m_;
  Eigen::Vector3i dims_;
  std::vector<int> first_;
  std::vector<int> tets_;
};

// The tet that contains p: of those that touch it (weights ≥ −1e-9: a point on a shared face
// belongs to either), the one whose smallest weight is largest; −1 if none.
int FindContainingTet(const TetMesh& mesh, const TetGrid& grid, const Vector3d& p_m) {
  constexpr double kInsideTolerance = 1e-9;
  int best_tet = -1;
  double best_min_weight = -kInsideTolerance;
  grid.ForEachCell(Eigen::AlignedBox3d(p_m, p_m), [&](int cell) {
    grid.ForEachTet(cell, [&](int t) {
      const double min_weight = CalcBarycentric(mesh, t, p_m).minCoeff();
      if (min_weight >= best_min_weight) {
        best_min_weight = min_weight;
        best_tet = t;
      }
    });
  });
  return best_tet;
}

// The tet nearest p among those whose boxes come within reach_m of it, and its distance; −1 if
// none. Of tets as near to round-off (p nearest a shared edge or node), the one whose weights
// stay smallest: a sliver's extrapolated weights can reach tens, and with them the contact rows'
// entries.
int FindNearestTet(const TetMesh& mesh, const TetGrid& grid, const Vector3d& p_m, double reach_m,
                   double* distance_m) {
  int best_tet = -1;
  double best_distance_m = std::numeric_limits<double>::infinity();
  double best_max_weight = std::numeric_limits<double>::infinity();
  const double tie_m = 1e-9 * std::max(1.0, p_m.cwiseAbs().maxCoeff());
  const Vector3d reach = Vector3d::Constant(reach_m);
  grid.ForEachCell(Eigen::AlignedBox3d(p_m - reach, p_m + reach), [&](int cell) {
    grid.ForEachTet(cell, [&](int t) {
      const double distance = CalcDistanceToTet(mesh, t, p_m);
      if (distance > best_distance_m + tie_m) return;
      const double max_weight = CalcBarycentric(mesh, t, p_m).cwiseAbs().maxCoeff();
      if (distance < best_distance_m - tie_m || max_weight < best_max_weight) {
        best_distance_m = std::min(best_distance_m, distance);
        best_max_weight = max_weight;
        best_tet = t;
      }
    });
  });
  *distance_m = best_distance_m;
  return best_tet;
}

// The reference coordinates ξ of p in quadratic tet t, X(ξ) = Σ_a N_a(ξ) X_a = p, by Newton's
// method from the corner tet's barycentric coordinates (exact at once where the tet is straight):
//   ξ ← ξ + (∂X/∂ξ)⁻¹ (p − X(ξ)),  ∂X/∂ξ = Σ_a X_a ∂N_a/∂ξ.
// Converged when the step is below 1e-12 of the tet's size; nullopt if it is not within 20 steps
// (or ∂X/∂ξ is singular: a tet curved past folding, which fem/curved_boundary.h refuses).
std::optional<Vector3d> FindQuadraticReferencePoint(const TetMesh& mesh, int t, const Vector3d& p_m,
                                                    const Vector4d& corner_weights) {
  Eigen::Matrix<double, 3, kP2Nodes> X;
  for (int a = 0; a < kP2Nodes; ++a) X.col(a) = mesh.rest_positions_m.col(mesh.node(a, t));
  Vector3d xi = corner_weights.tail<3>();
  for (int step = 0; step < 20; ++step) {
    const Vector3d residual_m = p_m - X * CalcP2ShapeFunctions(xi);
    const Eigen::Matrix3d dX_dxi = X * CalcP2ShapeDerivatives(xi);
    const Eigen::FullPivLU<Eigen::Matrix3d> lu(dX_dxi);
    if (!lu.isInvertible()) return std::nullopt;
    const Vector3d delta = lu.solve(residual_m);
    xi += delta;
    if (delta.norm() <= 1e-12) return xi;  // ξ is in units of the tet's size
  }
  return std::nullopt;
}

// A point's binding in a quadratic tet: the tet and the point's reference coordinates there.
struct QuadraticBinding {
  int tet = -1;
  Vector3d xi = Vector3d::Zero();
};

// The smallest barycentric coordinate of reference point ξ: ≥ 0 inside the (curved) tet.
double MinBarycentric(const Vector3d& xi) { return std::min(1.0 - xi.sum(), xi.minCoeff()); }

// The curved tet that holds p: of the tets whose boxes come within reach_m of p (and
// `straight_tet`, the one its corner tets chose), those where Newton's method finds ξ, the one
// with ξ deepest inside. A boundary tet curved outwards holds points that lie outside every corner
// tet, and near such a bulge the straight choice's quadratic map may have no preimage of p at all
// (the map folds outside its element: Newton cycled there on two_organs' liver).
std::optional<QuadraticBinding> BindInQuadraticTet(const TetMesh& mesh, const TetGrid& grid,
                                                   const Vector3d& p_m, double reach_m,
                                                   int straight_tet) {
  std::optional<QuadraticBinding> best;
  const auto consider = [&](int t) {
    const std::optional<Vector3d> xi =
        FindQuadraticReferencePoint(mesh, t, p_m, CalcBarycentric(mesh, t, p_m));
    if (xi && (!best || MinBarycentric(*xi) > MinBarycentric(best->xi)))
      best = QuadraticBinding{t, *xi};
  };
  consider(straight_tet);
  const Vector3d reach = Vector3d::Constant(reach_m);
  grid.ForEachCell(Eigen::AlignedBox3d(p_m - reach, p_m + reach), [&](int cell) {
    grid.ForEachTet(cell, [&](int t) {
      if (t != straight_tet) consider(t);
    });
  });
  return best;
}

double CalcMeanEdgeLength(const TetMesh& mesh) {
  static constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  double sum_m = 0.0;
  for (int t = 0; t < mesh.num_tets(); ++t)
    for (const auto& edge : kEdges)
      sum_m += (mesh.rest_positions_m.col(mesh.tets(edge[0], t)) -
                mesh.rest_positions_m.col(mesh.tets(edge[1], t)))
                   .norm();
  return mesh.num_tets() > 0 ? sum_m / (6.0 * mesh.num_tets()) : 0.0;
}

}  // namespace

double CalcDefaultMaxOutsideDistance(const TetMesh& mesh) { return 0.5 * CalcMeanEdgeLength(mesh); }

EmbeddedSurface EmbedSurface(const TetMesh& mesh, const Matrix3Xd& vertices_m,
                             const Matrix3Xi& triangles, double max_outside_m,
                             EmbeddingReport* report) {
  const Eigen::Index num_points = vertices_m.cols();
  if (num_points == 0 || triangles.cols() == 0)
    throw std::invalid_argument("the surface to embed has no triangles");
  if (mesh.num_tets() == 0)
    throw std::invalid_argument("the mesh to embed a surface in has no tets");
  if (triangles.minCoeff() < 0 || triangles.maxCoeff() >= num_points)
    throw std::invalid_argument("a triangle of the surface to embed names a vertex out of range");
  if (!(max_outside_m >= 0.0)) throw std::invalid_argument("max_outside_m must be >= 0");

  const double mean_edge_m = CalcMeanEdgeLength(mesh);
  const TetGrid grid(mesh, std::max(mean_edge_m, 1e-12));
  EmbeddedSurface surface;
  surface.triangles = triangles;
  const int k = mesh.nodes_per_tet();
  surface.nodes.resize(k, num_points);
  surface.weights.resize(k, num_points);
  EmbeddingReport found;
  found.max_allowed_m = max_outside_m;
  for (Eigen::Index p = 0; p < num_points; ++p) {
    const Vector3d p_m = vertices_m.col(p);
    int tet = FindContainingTet(mesh, grid, p_m);
    if (tet < 0) {
      double distance_m = 0.0;
      tet = FindNearestTet(mesh, grid, p_m, max_outside_m, &distance_m);
      if (tet < 0 || distance_m > max_outside_m) {
        std::ostringstream message;
        message << "surface vertex " << p + 1 << " at (" << p_m.x() << ", " << p_m.y() << ", "
                << p_m.z() << ") m lies "
                << (tet < 0 ? "more than " + std::to_string(max_outside_m)
                            : std::to_string(distance_m))
                << " m outside every tet (the limit is " << max_outside_m
                << " m; scenes take half the tets' mean edge): is the surface in the mesh's units "
                   "and placement?";
        throw std::invalid_argument(message.str());
      }
      ++found.num_outside;
      found.max_outside_m = std::max(found.max_outside_m, distance_m);
    }
    if (!mesh.is_quadratic()) {
      surface.nodes.col(p) = mesh.tets.col(tet);
      surface.weights.col(p) = CalcBarycentric(mesh, tet, p_m);
      continue;
    }
    // Every tet whose box comes within a tenth of the mean edge of the point is tried (Newton's
    // method ends in one step in a straight one): a curved side may hold what no corner tet does.
    const std::optional<QuadraticBinding> bound =
        BindInQuadraticTet(mesh, grid, p_m, 0.1 * mean_edge_m, tet);
    if (!bound) {
      std::ostringstream message;
      message << "surface vertex " << p + 1 << " at (" << p_m.x() << ", " << p_m.y() << ", "
              << p_m.z() << ") m: no quadratic tet near it maps a point onto it (Newton's method "
              << "did not converge in any)";
      throw std::invalid_argument(message.str());
    }
    for (int a = 0; a < k; ++a) surface.nodes(a, p) = mesh.node(a, bound->tet);
    surface.weights.col(p) = CalcP2ShapeFunctions(bound->xi);
  }
  if (report != nullptr) *report = found;
  return surface;
}

EmbeddedSurface MakeNodeSurface(const Matrix3Xi& triangles) {
  const int num_nodes = triangles.cols() > 0 ? triangles.maxCoeff() + 1 : 0;
  std::vector<int> point_of_node(static_cast<size_t>(num_nodes), -1);
  std::vector<int> nodes;
  EmbeddedSurface surface;
  surface.triangles.resize(3, triangles.cols());
  for (Eigen::Index f = 0; f < triangles.cols(); ++f)
    for (int k = 0; k < 3; ++k) {
      int& point = point_of_node[triangles(k, f)];
      if (point < 0) {
        point = static_cast<int>(nodes.size());
        nodes.push_back(triangles(k, f));
      }
      surface.triangles(k, f) = point;
    }
  surface.nodes.resize(4, static_cast<Eigen::Index>(nodes.size()));
  surface.weights.setZero(4, static_cast<Eigen::Index>(nodes.size()));
  for (size_t p = 0; p < nodes.size(); ++p) {
    surface.nodes.col(p).setConstant(nodes[p]);
    surface.weights(0, p) = 1.0;
  }
  return surface;
}

EmbeddedSurface MergeEmbeddedSurfaces(const std::vector<EmbeddedSurface>& parts,
                                      const std::vector<Matrix3Xi>& boundaries,
                                      const std::vector<int>& first_nodes) {
  if (boundaries.size() != parts.size() || first_nodes.size() != parts.size())
    throw std::invalid_argument("MergeEmbeddedSurfaces: one boundary and first node per part");
  if (std::all_of(parts.begin(), parts.end(), [](const auto& part) { return part.empty(); }))
    return {};
  std::vector<EmbeddedSurface> filled;
  int num_points = 0, num_triangles = 0;
  for (size_t i = 0; i < parts.size(); ++i) {
    filled.push_back(parts[i].empty() ? MakeNodeSurface(boundaries[i]) : parts[i]);
    num_points += filled.back().num_points();
    num_triangles += filled.back().num_triangles();
  }
  // Linear and quadratic parts together: rows for the larger, a short column padded with its
  // point's first node at weight 0 (read, never adding anything).
  int rows = 0;
  for (const EmbeddedSurface& part : filled) rows = std::max(rows, part.nodes_per_point());
  EmbeddedSurface merged;
  merged.nodes.resize(rows, num_points);
  merged.weights.setZero(rows, num_points);
  merged.triangles.resize(3, num_triangles);
  int point = 0, triangle = 0;
  for (size_t i = 0; i < filled.size(); ++i) {
    const EmbeddedSurface& part = filled[i];
    const int k = part.nodes_per_point();
    for (int p = 0; p < part.num_points(); ++p) {
      merged.nodes.col(point + p).setConstant(part.nodes(0, p) + first_nodes[i]);
      merged.nodes.col(point + p).head(k) = part.nodes.col(p).array() + first_nodes[i];
      merged.weights.col(point + p).head(k) = part.weights.col(p);
    }
    merged.triangles.middleCols(triangle, part.num_triangles()) = part.triangles.array() + point;
    point += part.num_points();
    triangle += part.num_triangles();
  }
  return merged;
}

void CalcEmbeddedPositions(const EmbeddedSurface& surface, const Eigen::VectorXd& x_nodes_m,
                           Eigen::VectorXd* x_points_m) {
  const Eigen::Index size = 3 * static_cast<Eigen::Index>(surface.num_points());
  if (x_points_m->size() != size) x_points_m->resize(size);
  for (int p = 0; p < surface.num_points(); ++p) {
    Vector3d x_m = Vector3d::Zero();
    for (int a = 0; a < surface.nodes_per_point(); ++a)
      x_m += surface.weights(a, p) * x_nodes_m.segment<3>(3 * surface.nodes(a, p));
    x_points_m->segment<3>(3 * p) = x_m;
  }
}

}  // namespace hapsim::fem
