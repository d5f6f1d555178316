#include "view/depth_cue.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hapsim::view {

double CastRay(const Eigen::Vector3d& origin_m, const Eigen::Vector3d& direction,
               const Matrix3Xd& vertices_m, const Matrix3Xi& triangles) {
  double nearest = std::numeric_limits<double>::infinity();
  for (Eigen::Index f = 0; f < triangles.cols(); ++f) {
    const Eigen::Vector3d a = vertices_m.col(triangles(0, f));
    const Eigen::Vector3d e1 = vertices_m.col(triangles(1, f)) - a;
    const Eigen::Vector3d e2 = vertices_m.col(triangles(2, f)) - a;
    // origin + t d = a + u e1 + v e2, solved by Cramer's rule with scalar triple products.
    const Eigen::Vector3d p = direction.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-300) continue;  // the ray lies in the triangle's plane
    const double inv_det = 1.0 / det;
    const Eigen::Vector3d s = origin_m - a;
    const double u = s.dot(p) * inv_det;
    if (u < 0.0 || u > 1.0) continue;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = direction.dot(q) * inv_det;
    if (v < 0.0 || u + v > 1.0) continue;
    const double t = e2.dot(q) * inv_det;
    if (t >= 0.0 && t < nearest) nearest = t;
  }
  return nearest;
}

DropHit CastDropLine(const Eigen::Vector3d& from_W_m, const std::vector<DropSurface>& surfaces) {
  DropHit hit;
  hit.from_W_m = from_W_m;
  const Eigen::Vector3d down_W(0.0, 0.0, -1.0);
  // Cast from kDropLineLift_m above: a tool resting on a surface, or pressed a little into it,
  // starts inside it, and the ray would land on its far side (a probe pressing a 6 mm clip read
  // "6.0 mm above the instrument"). A surface met within the lift is touching: distance 0.
  const Eigen::Vector3d start_W_m = from_W_m - kDropLineLift_m * down_W;
  double nearest = std::numeric_limits<double>::infinity();
  for (const DropSurface& surface : surfaces) {
    // In the surface's frame: the same line, so t is the same distance.
    const Eigen::Isometry3d X_SW = surface.X_WS.inverse();
    const double t =
        CastRay(X_SW * start_W_m, X_SW.linear() * down_W, *surface.vertices_m, *surface.triangles);
    if (t < nearest) {
      nearest = t;
      hit.name = surface.name;
    }
  }
  if (std::isfinite(nearest)) {
    hit.distance_m = std::max(0.0, nearest - kDropLineLift_m);
    hit.to_W_m = start_W_m + nearest * down_W;
  } else {
    hit.to_W_m = from_W_m;
  }
  return hit;
}

}  // namespace hapsim::view
