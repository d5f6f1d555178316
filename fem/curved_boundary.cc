#include "fem/curved_boundary.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core/closest_points.h"
#include "fem/quadratic_tet.h"

namespace hapsim::fem {
namespace {

// The closest point of the surface to p: every triangle, skipping those whose bounding box lies
// farther than the best found (a one-time pass at load, ~0.1 s for 10⁴ nodes against 10⁴
// triangles).
class ClosestSurfacePoint {
 public:
  ClosestSurfacePoint(const Matrix3Xd& vertices_m, const Matrix3Xi& triangles)
      : vertices_m_(vertices_m),
        triangles_(triangles),
        low_(3, triangles.cols()),
        high_(3, triangles.cols()) {
    for (Eigen::Index t = 0; t < triangles.cols(); ++t) {
      const Eigen::Vector3d a = vertices_m.col(triangles(0, t));
      const Eigen::Vector3d b = vertices_m.col(triangles(1, t));
      const Eigen::Vector3d c = vertices_m.col(triangles(2, t));
      low_.col(t) = a.cwiseMin(b).cwiseMin(c);
      high_.col(t) = a.cwiseMax(b).cwiseMax(c);
    }
  }

  Eigen::Vector3d Find(const Eigen::Vector3d& p) const {
    double best_sq = std::numeric_limits<double>::infinity();
    Eigen::Vector3d best = p;
    for (Eigen::Index t = 0; t < triangles_.cols(); ++t) {
      const Eigen::Vector3d outside = (low_.col(t) - p).cwiseMax(p - high_.col(t)).cwiseMax(0.0);
      if (outside.squaredNorm() >= best_sq) continue;
      const Eigen::Vector3d q = CalcClosestPointOnTriangle(p, vertices_m_.col(triangles_(0, t)),
                                                           vertices_m_.col(triangles_(1, t)),
                                                           vertices_m_.col(triangles_(2, t)))
                                    .point;
      if ((q - p).squaredNorm() < best_sq) {
        best_sq = (q - p).squaredNorm();
        best = q;
      }
    }
    return best;
  }

 private:
  const Matrix3Xd& vertices_m_;
  const Matrix3Xi& triangles_;
  Matrix3Xd low_, high_;  // each triangle's bounding box
};

// A move longer than this fraction of the edge is not made: the surface is then not the one the
// edge was cut from (an arc through the edge's ends whose midpoint is a quarter of the chord off it
// spans 106°, far more than a surface meshed at its own cell size bends over one edge).
constexpr double kMaxMoveOverEdge = 0.25;

// A curved tet must keep det(∂x/∂ξ), at its corners and quadrature points, at least this fraction
// of its straight corner tet's (constant) det: FindQuadraticTetProblem only refuses det ≤ 0, and a
// tet bent to near zero there would be valid but badly conditioned, stiffening the step.
constexpr double kMinDetOverStraight = 0.2;

bool IsBentTooFar(const P2Nodes& X_m) {
  if (FindQuadraticTetProblem(X_m)) return true;
  const double straight = CalcSignedVolume(X_m.col(0), X_m.col(1), X_m.col(2), X_m.col(3)) * 6.0;
  const auto det_at = [&](const Eigen::Vector3d& xi) {
    const Eigen::Matrix3d J = X_m * CalcP2ShapeDerivatives(xi);  // ∂x/∂ξ
    return J.determinant();
  };
  const Eigen::Vector3d corners[4] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                      Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
  for (const Eigen::Vector3d& xi : corners)
    if (det_at(xi) < kMinDetOverStraight * straight) return true;
  for (const QuadraturePoint& q : P2Quadrature())
    if (det_at(q.xi) < kMinDetOverStraight * straight) return true;
  return false;
}

bool AnyTetBentTooFar(const TetMesh& mesh, const std::vector<int>& tets) {
  for (int t : tets) {
    P2Nodes X_m;
    for (int a = 0; a < kP2Nodes; ++a) X_m.col(a) = mesh.rest_positions_m.col(mesh.node(a, t));
    if (IsBentTooFar(X_m)) return true;
  }
  return false;
}

}  // namespace

CurvedBoundaryReport MoveBoundaryEdgeNodesOntoSurface(const Matrix3Xd& surface_vertices_m,
                                                      const Matrix3Xi& surface_triangles,
                                                      TetMesh* mesh) {
  if (!mesh->is_quadratic())
    throw std::invalid_argument("MoveBoundaryEdgeNodesOntoSurface: the mesh has linear tets");
  if (surface_triangles.cols() == 0)
    throw std::invalid_argument("MoveBoundaryEdgeNodesOntoSurface: the surface has no triangle");
  // The tets around each edge node, and its edge's length.
  std::vector<std::vector<int>> tets_of_edge_node(static_cast<size_t>(mesh->num_nodes()));
  std::vector<double> edge_length_m(static_cast<size_t>(mesh->num_nodes()), 0.0);
  for (int t = 0; t < mesh->num_tets(); ++t)
    for (int k = 0; k < 6; ++k) {
      const int node = mesh->edge_nodes(k, t);
      tets_of_edge_node[node].push_back(t);
      edge_length_m[node] = (mesh->rest_positions_m.col(mesh->tets(kP2EdgeCorners[k][0], t)) -
                             mesh->rest_positions_m.col(mesh->tets(kP2EdgeCorners[k][1], t)))
                                .norm();
    }
  // The boundary's edge nodes, once each, in index order (the result does not depend on the
  // order of the boundary's triangles).
  const Matrix3Xi boundary = ExtractBoundarySurface(*mesh);
  std::vector<int> nodes(boundary.data(), boundary.data() + boundary.size());
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  nodes.erase(std::remove_if(nodes.begin(), nodes.end(),
                             [&](int n) { return tets_of_edge_node[n].empty(); }),
              nodes.end());

  CurvedBoundaryReport report;
  report.num_boundary_edge_nodes = static_cast<int>(nodes.size());
  const ClosestSurfacePoint surface(surface_vertices_m, surface_triangles);
  for (int node : nodes) {
    const Eigen::Vector3d midpoint = mesh->rest_positions_m.col(node);
    const Eigen::Vector3d target = surface.Find(midpoint);
    mesh->rest_positions_m.col(node) = target;
    if ((target - midpoint).norm() > kMaxMoveOverEdge * edge_length_m[node] ||
        AnyTetBentTooFar(*mesh, tets_of_edge_node[node])) {
      mesh->rest_positions_m.col(node) = midpoint;
      ++report.num_kept;
      continue;
    }
    ++report.num_moved;
    report.max_move_m = std::max(report.max_move_m, (target - midpoint).norm());
  }
  return report;
}

}  // namespace hapsim::fem
