#include "fem/model.h"

#include <Eigen/Dense>
#include <stdexcept>

namespace hapsim::fem {

int Model::num_fixed_nodes() const {
  int count = 0;
  for (int n = 0; n < num_nodes(); ++n) count += dof_is_fixed[3 * n] ? 1 : 0;
  return count;
}

Model MakeModel(TetMesh mesh, const Material& material, const std::vector<int>& fixed_nodes) {
  if (const auto problem = FindRestMeshProblem(mesh)) throw std::invalid_argument(*problem);
  Model model;
  model.mesh = std::move(mesh);
  model.material = material;
  model.surface_triangles = ExtractBoundarySurface(model.mesh);
  const int num_nodes = model.num_nodes();
  model.rest_positions_m =
      Eigen::Map<const Eigen::VectorXd>(model.mesh.rest_positions_m.data(), 3 * num_nodes);

  model.tet_rest.resize(model.num_tets());
  model.node_mass_kg = Eigen::VectorXd::Zero(num_nodes);
  for (int t = 0; t < model.num_tets(); ++t) {
    const Eigen::Vector4i tet = model.mesh.tets.col(t);
    Eigen::Matrix3d rest_edges_m;
    for (int i = 0; i < 3; ++i)
      rest_edges_m.col(i) =
          model.mesh.rest_positions_m.col(tet[i + 1]) - model.mesh.rest_positions_m.col(tet[0]);
    const Eigen::Matrix3d inverse_1_m = rest_edges_m.inverse();
    TetRestData& rest = model.tet_rest[t];
    rest.shape_gradients_1_m.rightCols<3>() = inverse_1_m.transpose();
    rest.shape_gradients_1_m.col(0) = -inverse_1_m.transpose().rowwise().sum();
    rest.volume_m3 = rest_edges_m.determinant() / 6.0;
    for (int a = 0; a < 4; ++a)
      model.node_mass_kg[tet[a]] += material.density_kg_m3 * rest.volume_m3 / 4.0;
  }
  model.dof_mass_kg = model.node_mass_kg.replicate(1, 3).transpose().reshaped();

  model.dof_is_fixed.assign(3 * num_nodes, 0);
  for (int n : fixed_nodes) {
    if (n < 0 || n >= num_nodes) throw std::invalid_argument("fixed node index out of range");
    for (int a = 0; a < 3; ++a) model.dof_is_fixed[3 * n + a] = 1;
  }
  return model;
}

std::vector<int> FindNodesInBox(const TetMesh& mesh, const Eigen::Vector3d& min_m,
                                const Eigen::Vector3d& max_m, double tolerance_m) {
  std::vector<int> nodes;
  for (int n = 0; n < mesh.num_nodes(); ++n) {
    const Eigen::Vector3d p_m = mesh.rest_positions_m.col(n);
    if (((p_m.array() >= min_m.array() - tolerance_m) &&
         (p_m.array() <= max_m.array() + tolerance_m))
            .all())
      nodes.push_back(n);
  }
  return nodes;
}

}  // namespace hapsim::fem
