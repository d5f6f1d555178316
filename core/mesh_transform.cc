#include "core/mesh_transform.h"

#include <Eigen/Geometry>

namespace hapsim {

void MeshTransform::Apply(Matrix3Xd* points_m) const {
  if (IsIdentity()) return;  // bit for bit the file's coordinates
  const double angle_rad = rotation_vector_rad.norm();
  const Eigen::Matrix3d R =
      angle_rad > 0.0
          ? Eigen::AngleAxisd(angle_rad, rotation_vector_rad / angle_rad).toRotationMatrix()
          : Eigen::Matrix3d::Identity();
  *points_m = ((scale * R) * *points_m).colwise() + translation_m;
}

}  // namespace hapsim
