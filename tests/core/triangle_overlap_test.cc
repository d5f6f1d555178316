// The exact triangle-versus-box and triangle-versus-cylinder tests of the surface tree's broad
// phase against an independent answer: each shape's signed distance (1-Lipschitz) sampled over a
// fine barycentric grid of the triangle. A sample inside the shape proves an overlap; all samples
// farther than the grid's covering radius prove there is none; in between the grid cannot
// decide and the case is skipped (rare, and counted). Plus the cases that clipping gets wrong
// first: a triangle through the cylinder with every corner outside, one seen edge-on, one lying
// on the cap, and one a hair beyond the side.
#include "core/triangle_overlap.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace hapsim {
namespace {

using Eigen::Vector3d;

double BoxDistance(const Vector3d& p, const Vector3d& half) {
  const Vector3d d = p.cwiseAbs() - half;
  return std::min(d.maxCoeff(), 0.0) + d.cwiseMax(0.0).norm();
}

double CylinderDistance(const Vector3d& p, double radius, double half_length) {
  const Eigen::Vector2d d(p.head<2>().norm() - radius, std::abs(p.z()) - half_length);
  return std::min(d.maxCoeff(), 0.0) + d.cwiseMax(0.0).norm();
}

// −1: the grid proves no overlap; +1: it proves one; 0: it cannot tell.
template <typename Distance>
int SampledVerdict(const Vector3d& a, const Vector3d& b, const Vector3d& c,
                   const Distance& distance) {
  constexpr int kN = 200;
  // Every point of the triangle lies within this of a grid point: a cell's circumradius (acute)
  // or half its longest edge (obtuse), at most the longest edge over √3.
  const double cover =
      std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()}) / (std::sqrt(3.0) * kN);
  double least = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= kN; ++i)
    for (int j = 0; i + j <= kN; ++j) {
      const Vector3d p =
          a + (static_cast<double>(i) / kN) * (b - a) + (static_cast<double>(j) / kN) * (c - a);
      least = std::min(least, distance(p));
    }
  if (least <= 0.0) return 1;
  return least > cover ? -1 : 0;
}

TEST(TriangleOverlap, AgreesWithTheSampledSignedDistanceOnRandomTriangles) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const Vector3d half(0.6, 0.3, 0.8);
  const double radius = 0.5, half_length = 0.7;
  int decided = 0, overlapping = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    // Triangles of every size near the shapes: some inside, some across, some beside.
    const Vector3d centre(unit(random), unit(random), unit(random));
    const double size = 0.05 + 0.8 * (0.5 + 0.5 * unit(random));
    const Vector3d a = centre + size * Vector3d(unit(random), unit(random), unit(random));
    const Vector3d b = centre + size * Vector3d(unit(random), unit(random), unit(random));
    const Vector3d c = centre + size * Vector3d(unit(random), unit(random), unit(random));
    const int box =
        SampledVerdict(a, b, c, [&](const Vector3d& p) { return BoxDistance(p, half); });
    const int cylinder = SampledVerdict(
        a, b, c, [&](const Vector3d& p) { return CylinderDistance(p, radius, half_length); });
    if (box != 0) {
      EXPECT_EQ(TriangleOverlapsBox(a, b, c, half), box > 0) << "trial " << trial;
      ++decided, overlapping += box > 0;
    }
    if (cylinder != 0) {
      EXPECT_EQ(TriangleOverlapsCylinder(a, b, c, radius, half_length), cylinder > 0)
          << "trial " << trial;
      ++decided, overlapping += cylinder > 0;
    }
  }
  EXPECT_GT(decided, 5900);             // the grid decides nearly every case
  EXPECT_GT(overlapping, decided / 5);  // both answers are common
  EXPECT_LT(overlapping, 4 * decided / 5);
}

TEST(TriangleOverlap, CasesWhereNoCornerIsInside) {
  const double r = 1.0, h = 1.0;
  // Through the cylinder's middle, every corner far outside it: the shadow covers the axis.
  EXPECT_TRUE(
      TriangleOverlapsCylinder(Vector3d(-5, -5, 0), Vector3d(5, -5, 0), Vector3d(0, 5, 0), r, h));
  // Seen edge-on (a vertical triangle) passing the axis, and 1e-9 beyond the side.
  EXPECT_TRUE(TriangleOverlapsCylinder(Vector3d(-3, 0.5, -3), Vector3d(3, 0.5, -3),
                                       Vector3d(0, 0.5, 3), r, h));
  EXPECT_FALSE(TriangleOverlapsCylinder(Vector3d(-3, 1 + 1e-9, -3), Vector3d(3, 1 + 1e-9, -3),
                                        Vector3d(0, 1 + 1e-9, 3), r, h));
  // Lying on the cap (closed shape) and 1e-9 above it.
  EXPECT_TRUE(
      TriangleOverlapsCylinder(Vector3d(-5, -5, 1), Vector3d(5, -5, 1), Vector3d(0, 5, 1), r, h));
  EXPECT_FALSE(TriangleOverlapsCylinder(Vector3d(-5, -5, 1 + 1e-9), Vector3d(5, -5, 1 + 1e-9),
                                        Vector3d(0, 5, 1 + 1e-9), r, h));
  // A large triangle across a box's corner region without a corner inside, and one just past
  // the corner along the diagonal (its plane x + y + z = 3 + 1e-9 misses the box).
  const Vector3d half(1, 1, 1);
  EXPECT_TRUE(
      TriangleOverlapsBox(Vector3d(2.9, 0, 0), Vector3d(0, 2.9, 0), Vector3d(0, 0, 2.9), half));
  const double s = 3.0 + 1e-9;
  EXPECT_FALSE(TriangleOverlapsBox(Vector3d(s, 0, 0), Vector3d(0, s, 0), Vector3d(0, 0, s), half));
}

}  // namespace
}  // namespace hapsim
