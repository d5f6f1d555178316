#pragma once
// The tool's depth cue (issue 26): on a flat picture a trainee cannot tell how far in front of the
// organ the tool is. A drop line from the tool's underside below its centre straight down (−z,
// the direction of gravity in every scene) to the first surface beneath it, a shadow ring where it
// lands, and the distance in the gauge show it (view/scene_painter.cc draws them).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <limits>
#include <string>
#include <vector>

#include "core/eigen_types.h"

namespace hapsim::view {

// The smallest t ≥ 0 at which origin + t·direction meets a triangle (either side; Möller and
// Trumbore, "Fast, minimum storage ray/triangle intersection", 1997), or +∞ if none.
// vertices_m: (3 x V); triangles: (3 x F) vertex indices.
double CastRay(const Eigen::Vector3d& origin_m, const Eigen::Vector3d& direction,
               const Matrix3Xd& vertices_m, const Matrix3Xi& triangles);

// A surface the drop line may land on, posed in the world: vertices in its own frame.
struct DropSurface {
  std::string name;  // for the gauge: "liver", "tray", …
  const Matrix3Xd* vertices_m = nullptr;
  const Matrix3Xi* triangles = nullptr;
  Eigen::Isometry3d X_WS = Eigen::Isometry3d::Identity();
};

struct DropHit {
  Eigen::Vector3d from_W_m = Eigen::Vector3d::Zero();           // where the line starts
  Eigen::Vector3d to_W_m = Eigen::Vector3d::Zero();             // where the line lands
  double distance_m = std::numeric_limits<double>::infinity();  // +∞: nothing below
  std::string name;                                             // the surface it lands on
};

// The drop line from `from_W_m` straight down to the nearest of `surfaces`.
// The drop line from from_W_m (the tool's underside) straight down, cast from kDropLineLift_m
// above it so that a surface the tool rests on or presses into is met at its top (distance 0).
inline constexpr double kDropLineLift_m = 0.002;
DropHit CastDropLine(const Eigen::Vector3d& from_W_m, const std::vector<DropSurface>& surfaces);

}  // namespace hapsim::view
