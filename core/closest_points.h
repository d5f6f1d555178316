#pragma once
// Closest points between a point and a triangle and between two segments: the geometric kernels
// that contact detection (contact/), the god-object proxy and the embedding of surfaces in tets
// (fem/surface_embedding.h) share.

#include <Eigen/Core>

namespace hapsim {

// Closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection, §5.1.5), its
// barycentric weights (≥ 0, sum 1) and the feature it lies on.
struct TrianglePoint {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d weights = Eigen::Vector3d(1.0, 0.0, 0.0);  // of a, b, c
  int feature = 6;  // 0..2 vertex k; 3..5 edge k − 3 = (k, k+1 mod 3); 6 the face interior
};
TrianglePoint CalcClosestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                         const Eigen::Vector3d& b, const Eigen::Vector3d& c);

// Closest points of segments p1 + s (q1 − p1) and p2 + t (q2 − p2), s, t ∈ [0, 1] (Ericson,
// Real-Time Collision Detection, §5.1.9, ClosestPtSegmentSegment). Parallel segments: one of the
// closest pairs (s = 0 unless clamped). A segment collapsed to a point is handled as that point.
struct SegmentPoints {
  Eigen::Vector3d point1 = Eigen::Vector3d::Zero();  // p1 + s (q1 − p1)
  Eigen::Vector3d point2 = Eigen::Vector3d::Zero();  // p2 + t (q2 − p2)
  double s = 0.0;
  double t = 0.0;
};
SegmentPoints CalcClosestPointsOfSegments(const Eigen::Vector3d& p1, const Eigen::Vector3d& q1,
                                          const Eigen::Vector3d& p2, const Eigen::Vector3d& q2);

}  // namespace hapsim
