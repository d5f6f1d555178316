// The tool's drop line (view/depth_cue.h) against closed forms: a box's top face lies at its
// centre's height plus its half height however it is turned about the vertical, the line lands
// on the nearest of several surfaces, and misses what is not below it.
#include "view/depth_cue.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/shape_mesh.h"
#include "core/tool_shape.h"

namespace hapsim::view {
namespace {

TriangleMesh BoxMesh(const Eigen::Vector3d& half_extents_m) {
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m = half_extents_m;
  return MakeShapeMesh(box);
}

Eigen::Isometry3d Pose(double yaw_rad, const Eigen::Vector3d& x_m) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  X.translation() = x_m;
  return X;
}

TEST(DepthCueTest, CastRayMeetsTheNearestFaceOrNothing) {
  const TriangleMesh box = BoxMesh({0.1, 0.2, 0.05});
  const Eigen::Vector3d down(0.0, 0.0, -1.0);
  EXPECT_NEAR(CastRay({0.03, -0.07, 0.3}, down, box.vertices_m, box.triangles), 0.25, 1e-15);
  // From inside, the far (bottom) face.
  EXPECT_NEAR(CastRay({0.03, -0.07, 0.0}, down, box.vertices_m, box.triangles), 0.05, 1e-15);
  // Beside it, or pointing away: nothing.
  EXPECT_TRUE(std::isinf(CastRay({0.11, 0.0, 0.3}, down, box.vertices_m, box.triangles)));
  EXPECT_TRUE(std::isinf(CastRay({0.0, 0.0, 0.3}, -down, box.vertices_m, box.triangles)));
  // Along a slant: the top face at z = 0.05 from (0, 0, 0.15) along (1, 0, −1)/√2 is √2 · 0.1 away.
  EXPECT_NEAR(CastRay({0.0, 0.0, 0.15}, Eigen::Vector3d(1.0, 0.0, -1.0).normalized(),
                      box.vertices_m, box.triangles),
              std::sqrt(2.0) * 0.1, 1e-15);
}

TEST(DepthCueTest, TheDropLineLandsOnTheNearestSurfaceBelow) {
  const TriangleMesh organ = BoxMesh({0.03, 0.02, 0.01});
  const TriangleMesh tray = BoxMesh({0.2, 0.2, 0.005});
  std::vector<DropSurface> surfaces = {
      {"tray", &tray.vertices_m, &tray.triangles, Pose(0.0, {0.0, 0.0, -0.005})},
      {"organ", &organ.vertices_m, &organ.triangles, Pose(0.6, {0.05, 0.0, 0.02})}};
  // Above the organ (turned 0.6 rad about z: its top still at 0.02 + 0.01).
  const DropHit on_organ = CastDropLine({0.05, 0.005, 0.1}, surfaces);
  EXPECT_EQ(on_organ.name, "organ");
  EXPECT_NEAR(on_organ.distance_m, 0.1 - 0.03, 1e-15);
  EXPECT_NEAR(on_organ.to_W_m.z(), 0.03, 1e-15);
  // Beside it: the tray's top at z = 0.
  const DropHit on_tray = CastDropLine({-0.1, 0.1, 0.1}, surfaces);
  EXPECT_EQ(on_tray.name, "tray");
  EXPECT_NEAR(on_tray.distance_m, 0.1, 1e-15);
  // Off the tray: nothing below, the line ends where it starts.
  const DropHit nothing = CastDropLine({0.5, 0.0, 0.1}, surfaces);
  EXPECT_TRUE(std::isinf(nothing.distance_m));
  EXPECT_TRUE(nothing.name.empty());
  EXPECT_EQ(nothing.to_W_m, nothing.from_W_m);
  // Resting on the organ's top, or pressed 0.5 mm into it: touching it, not above its bottom
  // (a line cast from inside met the far face first: the organ's 20 mm read as the distance).
  for (const double into_m : {0.0, 0.0005}) {
    const DropHit touching = CastDropLine({0.05, 0.005, 0.03 - into_m}, surfaces);
    EXPECT_EQ(touching.name, "organ");
    EXPECT_NEAR(touching.distance_m, 0.0, 1e-15) << into_m;
    EXPECT_NEAR(touching.to_W_m.z(), 0.03, 1e-15);
  }
}

}  // namespace
}  // namespace hapsim::view
