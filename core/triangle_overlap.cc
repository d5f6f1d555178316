#include "core/triangle_overlap.h"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>

namespace hapsim {
namespace {

using Eigen::Vector3d;

// A convex polygon: a triangle cut by up to six planes has at most nine corners. Rounding can
// make a nearly flat corner cross a plane twice more; a polygon that would outgrow its room is
// taken to overlap (`overflow`), which only hands the narrow phase one more face to decide.
struct Polygon {
  std::array<Vector3d, 24> corners;  // room for any clip of up to twelve corners
  int size = 0;
  bool overflow = false;
};

// Keeps the part of *polygon with sign · (p[axis] − bound) ≤ 0 (sign = +1: p ≤ bound; −1: p ≥
// bound): every edge crossing the plane contributes its crossing point.
void ClipToHalfSpace(int axis, double bound, double sign, Polygon* polygon) {
  Polygon kept;
  if (2 * polygon->size > static_cast<int>(kept.corners.size())) {
    polygon->overflow = true;
    return;
  }
  for (int i = 0; i < polygon->size; ++i) {
    const Vector3d& p = polygon->corners[i];
    const Vector3d& q = polygon->corners[(i + 1) % polygon->size];
    const double dp = sign * (p[axis] - bound), dq = sign * (q[axis] - bound);
    if (dp <= 0.0) kept.corners[kept.size++] = p;
    if ((dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0))
      kept.corners[kept.size++] = p + (dp / (dp - dq)) * (q - p);
  }
  *polygon = kept;
}

void ClipToSlab(int axis, double half_width, Polygon* polygon) {
  ClipToHalfSpace(axis, half_width, 1.0, polygon);
  if (polygon->size > 0 && !polygon->overflow) ClipToHalfSpace(axis, -half_width, -1.0, polygon);
}

Polygon MakeTriangle(const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  Polygon polygon;
  polygon.corners[0] = a, polygon.corners[1] = b, polygon.corners[2] = c;
  polygon.size = 3;
  return polygon;
}

// Squared distance from the origin to the segment p q, in the xy plane.
double CalcSquaredDistanceToSegmentXy(const Vector3d& p, const Vector3d& q) {
  const Eigen::Vector2d p2 = p.head<2>(), d = q.head<2>() - p2;
  const double length_sq = d.squaredNorm();
  const double t = length_sq > 0.0 ? std::clamp(-p2.dot(d) / length_sq, 0.0, 1.0) : 0.0;
  return (p2 + t * d).squaredNorm();
}

// Whether the polygon's shadow on the xy plane covers the origin: the origin on the same side of
// every edge. A shadow of no area (a polygon seen edge-on) covers nothing the edges do not reach.
bool ShadowCoversOrigin(const Polygon& polygon) {
  bool any_positive = false, any_negative = false;
  for (int i = 0; i < polygon.size; ++i) {
    const Vector3d& p = polygon.corners[i];
    const Vector3d& q = polygon.corners[(i + 1) % polygon.size];
    const double cross = p.x() * q.y() - p.y() * q.x();  // (p × q)_z: origin left of p → q if > 0
    any_positive |= cross > 0.0;
    any_negative |= cross < 0.0;
  }
  return any_positive != any_negative;
}

}  // namespace

bool TriangleOverlapsBox(const Vector3d& a, const Vector3d& b, const Vector3d& c,
                         const Vector3d& half_extents) {
  Polygon polygon = MakeTriangle(a, b, c);
  for (int axis = 0; axis < 3 && polygon.size > 0 && !polygon.overflow; ++axis)
    ClipToSlab(axis, half_extents[axis], &polygon);
  return polygon.size > 0 || polygon.overflow;
}

bool TriangleOverlapsCylinder(const Vector3d& a, const Vector3d& b, const Vector3d& c,
                              double radius, double half_length) {
  Polygon polygon = MakeTriangle(a, b, c);
  ClipToSlab(2, half_length, &polygon);
  if (polygon.overflow) return true;
  if (polygon.size == 0) return false;
  const double radius_sq = radius * radius;
  for (int i = 0; i < polygon.size; ++i)
    if (CalcSquaredDistanceToSegmentXy(polygon.corners[i],
                                       polygon.corners[(i + 1) % polygon.size]) <= radius_sq)
      return true;
  return ShadowCoversOrigin(polygon);
}

}  // namespace hapsim
