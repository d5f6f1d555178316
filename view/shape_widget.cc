#include "view/shape_widget.h"

#include <cmath>

#include "contact/tool_distance.h"

namespace hapsim::view {
namespace {

// A flat disc of `radius_m` at height z, normal ±z, as a triangle fan.
cv::viz::WMesh MakeDisc(double radius_m, double z_m, int sides, const cv::viz::Color& color) {
  cv::viz::Mesh mesh;
  mesh.cloud.create(1, sides + 1, CV_64FC3);
  mesh.cloud.at<cv::Vec3d>(0, 0) = cv::Vec3d(0, 0, z_m);
  for (int k = 0; k < sides; ++k) {
    const double angle = 2.0 * M_PI * k / sides;
    mesh.cloud.at<cv::Vec3d>(0, k + 1) =
        cv::Vec3d(radius_m * std::cos(angle), radius_m * std::sin(angle), z_m);
  }
  mesh.polygons.create(1, 4 * sides, CV_32SC1);
  for (int k = 0; k < sides; ++k) {
    int* triangle = mesh.polygons.ptr<int>(0) + 4 * k;
    triangle[0] = 3;
    triangle[1] = 0;
    triangle[2] = k + 1;
    triangle[3] = (k + 1) % sides + 1;
  }
  cv::viz::WMesh disc(mesh);
  disc.setColor(color);
  return disc;
}

}  // namespace

cv::Vec3d ToVec(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

ToolShape InflateShape(ToolShape shape, double fraction) {
  const double grow_m = fraction * contact::ToolDistanceField(shape).bounding_radius_m();
  shape.radius_m += grow_m;
  shape.length_m += shape.kind == ToolShape::Kind::kCylinder ? 2.0 * grow_m : 0.0;
  shape.edge_radius_m = 0.0;
  shape.half_extents_m.array() += grow_m;
  shape.mesh.vertices_m *= 1.0 + fraction;
  return shape;
}

Eigen::Isometry3d ToIsometry(const double x_W_m[3], const double q[4]) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
  X.translation() = Eigen::Vector3d(x_W_m[0], x_W_m[1], x_W_m[2]);
  return X;
}

cv::Affine3d ToAffine(const double x_W_m[3], const double q[4]) {
  const Eigen::Matrix3d R = ToIsometry(x_W_m, q).linear();
  cv::Matx33d rotation;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) rotation(i, j) = R(i, j);
  return cv::Affine3d(rotation, cv::Vec3d(x_W_m[0], x_W_m[1], x_W_m[2]));
}

cv::viz::Widget3D MakeShapeWidget(const ToolShape& shape, const cv::viz::Color& color,
                                  bool wireframe) {
  cv::viz::WWidgetMerger merged;
  const double half_length = 0.5 * shape.length_m;
  switch (shape.kind) {
    case ToolShape::Kind::kSphere:
      merged.addWidget(cv::viz::WSphere(cv::Point3d(0, 0, 0), shape.radius_m, 24, color));
      break;
    case ToolShape::Kind::kCapsule:
      merged.addWidget(cv::viz::WCylinder(cv::Point3d(0, 0, -half_length),
                                          cv::Point3d(0, 0, half_length), shape.radius_m, 32,
                                          color));
      for (const double z : {-half_length, half_length})
        merged.addWidget(cv::viz::WSphere(cv::Point3d(0, 0, z), shape.radius_m, 24, color));
      break;
    case ToolShape::Kind::kCylinder:
      merged.addWidget(cv::viz::WCylinder(cv::Point3d(0, 0, -half_length),
                                          cv::Point3d(0, 0, half_length), shape.radius_m, 48,
                                          color));
      // WCylinder is an open tube (and viz circles are rings): close it with two discs.
      for (const double z : {-half_length, half_length})
        merged.addWidget(MakeDisc(shape.radius_m, z, 48, color));
      break;
    case ToolShape::Kind::kBox: {
      const Eigen::Vector3d& h = shape.half_extents_m;
      merged.addWidget(cv::viz::WCube(cv::Point3d(-h.x(), -h.y(), -h.z()),
                                      cv::Point3d(h.x(), h.y(), h.z()), false, color));
      break;
    }
    case ToolShape::Kind::kMesh: {
      cv::viz::Mesh mesh;
      mesh.cloud.create(1, static_cast<int>(shape.mesh.vertices_m.cols()), CV_64FC3);
      for (int v = 0; v < mesh.cloud.cols; ++v)
        mesh.cloud.at<cv::Vec3d>(0, v) = ToVec(shape.mesh.vertices_m.col(v));
      mesh.polygons.create(1, 4 * static_cast<int>(shape.mesh.triangles.cols()), CV_32SC1);
      for (int f = 0; f < shape.mesh.triangles.cols(); ++f) {
        mesh.polygons.at<int>(0, 4 * f) = 3;
        for (int k = 0; k < 3; ++k)
          mesh.polygons.at<int>(0, 4 * f + 1 + k) = shape.mesh.triangles(k, f);
      }
      cv::viz::WMesh widget(mesh);
      widget.setColor(color);
      merged.addWidget(widget);
      break;
    }
  }
  merged.finalize();
  merged.setColor(color);  // the parts' colours do not all survive the merge
  merged.setRenderingProperty(cv::viz::SHADING, cv::viz::SHADING_PHONG);
  if (wireframe)
    merged.setRenderingProperty(cv::viz::REPRESENTATION, cv::viz::REPRESENTATION_WIREFRAME);
  return merged;
}

}  // namespace hapsim::view
