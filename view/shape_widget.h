#pragma once
// viz widgets of the tool's and the rigid objects' shapes, and the conversions the painter
// needs (view/scene_painter.h).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/viz.hpp>

#include "core/tool_shape.h"

namespace hapsim::view {

cv::Vec3d ToVec(const Eigen::Vector3d& p);

// The pose x, q (w, x, y, z; normalised here) as Eigen and as viz want it.
Eigen::Isometry3d ToIsometry(const double x_W_m[3], const double q[4]);
cv::Affine3d ToAffine(const double x_W_m[3], const double q[4]);

// A viz widget of `shape` (core/tool_shape.h) in its own frame; wireframe for the ghost.
cv::viz::Widget3D MakeShapeWidget(const ToolShape& shape, const cv::viz::Color& color,
                                  bool wireframe);

// `shape` grown by `fraction` of its bounding radius on every side (a mesh: scaled), so that the
// device's ghost, drawn as lines, does not lie on the tool's surface where the two coincide: there
// the depth test would pick between them by rounding, differently from one window to the next.
ToolShape InflateShape(ToolShape shape, double fraction);

}  // namespace hapsim::view
