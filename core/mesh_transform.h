#pragma once
// A user's mesh file placed in hapsim's frame and units (issue 26): organ meshes from segmentation
// often come in millimetres or centimetres, with y up. A point p of the file goes to
//
//   p' = R (s p) + t,   s > 0 (the `units`' factor times transform.scale), R from a rotation
//                       vector (Rodrigues), t in metres,
//
// which keeps every tet's and triangle's orientation (s > 0, det R = 1).

#include <Eigen/Core>

#include "core/eigen_types.h"

namespace hapsim {

struct MeshTransform {
  double scale = 1.0;
  Eigen::Vector3d rotation_vector_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d translation_m = Eigen::Vector3d::Zero();

  bool IsIdentity() const {
    return scale == 1.0 && rotation_vector_rad.isZero(0.0) && translation_m.isZero(0.0);
  }
  // Every column of *points_m (3 × N) as above. Precondition: scale > 0 (checked by the caller).
  void Apply(Matrix3Xd* points_m) const;
};

}  // namespace hapsim
