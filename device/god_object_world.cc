#include "device/god_object_world.h"

#include "core/shape_mesh.h"

namespace hapsim::device {

GodObjectWorld::GodObjectWorld(const contact::GodObjectParams& params, const fem::Model* body,
                               const std::vector<contact::RigidObject>& objects)
    : god_(params) {
  for (const contact::RigidObject& object : objects)
    object_meshes_.push_back(god_.AddMesh(MakeShapeMesh(object.shape), object.X_WO));
  if (body != nullptr) {
    TriangleMesh surface;
    surface.vertices_m = Eigen::Map<const Matrix3Xd>(body->rest_positions_m.data(), 3,
                                                     body->rest_positions_m.size() / 3);
    surface.triangles = body->surface_triangles;
    body_mesh_ = god_.AddMesh(surface, Eigen::Isometry3d::Identity());
    body_vertices_m_ = surface.vertices_m;
  }
}

void GodObjectWorld::SetWorld(const Eigen::VectorXd& x_body_m,
                              const std::vector<Eigen::Isometry3d>& X_WO) {
  for (size_t i = 0; i < X_WO.size() && i < object_meshes_.size(); ++i)
    god_.SetMeshPose(object_meshes_[i], X_WO[i]);
  if (body_mesh_ >= 0) {
    body_vertices_m_ = Eigen::Map<const Matrix3Xd>(x_body_m.data(), 3, x_body_m.size() / 3);
    god_.SetMeshVertices(body_mesh_, body_vertices_m_);
  }
}

}  // namespace hapsim::device
