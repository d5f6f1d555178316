#include "core/closest_points.h"

#include <algorithm>

namespace hapsim {

using Eigen::Vector3d;

TrianglePoint CalcClosestPointOnTriangle(const Vector3d& p, const Vector3d& a, const Vector3d& b,
                                         const Vector3d& c) {
  const auto make = [&](double wa, double wb, double wc, int feature) {
    return TrianglePoint{wa * a + wb * b + wc * c, Vector3d(wa, wb, wc), feature};
  };
  const Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return make(1.0, 0.0, 0.0, 0);
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return make(0.0, 1.0, 0.0, 1);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double t = d1 / (d1 - d3);
    return make(1.0 - t, t, 0.0, 3);
  }
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return make(0.0, 0.0, 1.0, 2);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double t = d2 / (d2 - d6);
    return make(1.0 - t, 0.0, t, 5);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return make(0.0, 1.0 - t, t, 4);
  }
  const double denominator = 1.0 / (va + vb + vc);
  const double v = vb * denominator, w = vc * denominator;
  return make(1.0 - v - w, v, w, 6);
}

SegmentPoints CalcClosestPointsOfSegments(const Vector3d& p1, const Vector3d& q1,
                                          const Vector3d& p2, const Vector3d& q2) {
  const Vector3d d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0.0, t = 0.0;
  if (a > 0.0 && e > 0.0) {
    const double b = d1.dot(d2), c = d1.dot(r), denominator = a * e - b * b;  // ≥ 0
    // Closest point of line 1 to line 2, clamped; for parallel lines any s will do: s = 0.
    if (denominator > 0.0) s = std::clamp((b * f - c * e) / denominator, 0.0, 1.0);
    t = (b * s + f) / e;
    // t outside [0, 1]: clamp it and recompute s for the clamped t (Ericson's order).
    if (t < 0.0) {
      t = 0.0;
      s = std::clamp(-c / a, 0.0, 1.0);
    } else if (t > 1.0) {
      t = 1.0;
      s = std::clamp((b - c) / a, 0.0, 1.0);
    }
  } else if (a > 0.0) {  // segment 2 is a point
    s = std::clamp(-d1.dot(r) / a, 0.0, 1.0);
  } else if (e > 0.0) {  // segment 1 is a point
    t = std::clamp(f / e, 0.0, 1.0);
  }
  return SegmentPoints{p1 + s * d1, p2 + t * d2, s, t};
}

}  // namespace hapsim
