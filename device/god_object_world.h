#pragma once
// The world of the godobject mode (paper 004; contact/god_object.h): the god-object's meshes
// made from a scene, and moved to where the last visual frame left things. Each rigid object is
// its shape's triangle surface (core/shape_mesh.h) at its pose; the deformable body is its
// surface triangles on its nodes, replaced at every frame (rigid between frames, as the other
// 1 kHz geometric modes see it).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "contact/god_object.h"
#include "contact/rigid_objects.h"
#include "core/eigen_types.h"
#include "fem/model.h"

namespace hapsim::device {

class GodObjectWorld {
 public:
  // `body` null: no deformable body. Throws std::invalid_argument as GodObject does.
  GodObjectWorld(const contact::GodObjectParams& params, const fem::Model* body,
                 const std::vector<contact::RigidObject>& objects);

  // The last visual frame's body node positions (3N, world, m; ignored without a body) and
  // object poses. At the visual rate: refits the body's tree.
  void SetWorld(const Eigen::VectorXd& x_body_m, const std::vector<Eigen::Isometry3d>& X_WO);

  contact::GodObject& god_object() { return god_; }
  const contact::GodObject& god_object() const { return god_; }

 private:
  contact::GodObject god_;
  int body_mesh_ = -1;
  std::vector<int> object_meshes_;
  Matrix3Xd body_vertices_m_;  // (3 x N) scratch: the body's nodes as the mesh's vertices
};

}  // namespace hapsim::device
