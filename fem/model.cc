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
  if (model.is_quadratic()) model.quadratic_stiffness.reserve(model.num_tets());
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
    rest.lame_mu_Pa = material.lame_mu_Pa();
    rest.lame_lambda_Pa = material.lame_lambda_Pa();
    if (model.is_quadratic()) {
      P2Nodes X_m;
      for (int a = 0; a < kP2Nodes; ++a)
        X_m.col(a) = model.mesh.rest_positions_m.col(model.mesh.node(a, t));
      const QuadraticTetRest quadratic =
          MakeQuadraticTetRest(X_m, rest.lame_mu_Pa, rest.lame_lambda_Pa, material.density_kg_m3);
      model.quadratic_stiffness.push_back(PackP2Stiffness(quadratic.stiffness));
      for (int a = 0; a < kP2Nodes; ++a)
        model.node_mass_kg[model.mesh.node(a, t)] += quadratic.lumped_mass_kg[a];
    } else {
      for (int a = 0; a < 4; ++a)
        model.node_mass_kg[tet[a]] += material.density_kg_m3 * rest.volume_m3 / 4.0;
    }
  }
  model.dof_mass_kg = model.node_mass_kg.replicate(1, 3).transpose().reshaped();

  model.dof_is_fixed.assign(3 * num_nodes, 0);
  for (int n : fixed_nodes) {
    if (n < 0 || n >= num_nodes) throw std::invalid_argument("fixed node index out of range");
    for (int a = 0; a < 3; ++a) model.dof_is_fixed[3 * n + a] = 1;
  }
  return model;
}

Model MergeModels(const std::vector<Model>& models) {
  if (models.empty()) throw std::invalid_argument("MergeModels: no model");
  Model merged;
  merged.material = models.front().material;
  int num_nodes = 0, num_tets = 0, num_faces = 0;
  for (const Model& model : models) {
    if (model.material.rayleigh_alpha_1_s != merged.material.rayleigh_alpha_1_s ||
        model.material.rayleigh_beta_s != merged.material.rayleigh_beta_s)
      throw std::invalid_argument(
          "the deformable objects must share their Rayleigh damping (rayleigh_alpha_1_s, "
          "rayleigh_beta_s): one damping serves the implicit step's matrix");
    if (model.is_quadratic() != models.front().is_quadratic())
      throw std::invalid_argument(
          "the deformable objects must all have linear tets or all quadratic ones (element)");
    num_nodes += model.num_nodes();
    num_tets += model.num_tets();
    num_faces += static_cast<int>(model.surface_triangles.cols());
  }
  merged.mesh.rest_positions_m.resize(3, num_nodes);
  merged.mesh.tets.resize(4, num_tets);
  if (models.front().is_quadratic()) merged.mesh.edge_nodes.resize(6, num_tets);
  merged.surface_triangles.resize(3, num_faces);
  merged.node_mass_kg.resize(num_nodes);
  int node = 0, tet = 0, face = 0;
  for (const Model& model : models) {
    merged.mesh.rest_positions_m.middleCols(node, model.num_nodes()) = model.mesh.rest_positions_m;
    merged.mesh.tets.middleCols(tet, model.num_tets()) = model.mesh.tets.array() + node;
    if (model.is_quadratic()) {
      merged.mesh.edge_nodes.middleCols(tet, model.num_tets()) =
          model.mesh.edge_nodes.array() + node;
      merged.quadratic_stiffness.insert(merged.quadratic_stiffness.end(),
                                        model.quadratic_stiffness.begin(),
                                        model.quadratic_stiffness.end());
    }
    merged.surface_triangles.middleCols(face, model.surface_triangles.cols()) =
        model.surface_triangles.array() + node;
    merged.node_mass_kg.segment(node, model.num_nodes()) = model.node_mass_kg;
    merged.tet_rest.insert(merged.tet_rest.end(), model.tet_rest.begin(), model.tet_rest.end());
    merged.dof_is_fixed.insert(merged.dof_is_fixed.end(), model.dof_is_fixed.begin(),
                               model.dof_is_fixed.end());
    node += model.num_nodes();
    tet += model.num_tets();
    face += static_cast<int>(model.surface_triangles.cols());
  }
  // Contacts are found on every object alike: on the boundary of those without a collision
  // surface when another has one.
  std::vector<EmbeddedSurface> collision_surfaces;
  std::vector<Matrix3Xi> boundaries;
  std::vector<int> first_nodes;
  int first_node = 0;
  for (const Model& model : models) {
    collision_surfaces.push_back(model.collision_surface);
    boundaries.push_back(model.surface_triangles);
    first_nodes.push_back(first_node);
    first_node += model.num_nodes();
  }
  if (models.size() > 1) merged.object_first_nodes = first_nodes;
  merged.collision_surface = MergeEmbeddedSurfaces(collision_surfaces, boundaries, first_nodes);
  merged.dof_mass_kg = merged.node_mass_kg.replicate(1, 3).transpose().reshaped();
  merged.rest_positions_m =
      Eigen::Map<const Eigen::VectorXd>(merged.mesh.rest_positions_m.data(), 3 * num_nodes);
  return merged;
}

std::vector<int> FindFreeSurfaceNodes(const Model& model) {
  std::vector<std::uint8_t> on_surface(static_cast<size_t>(model.num_nodes()), 0);
  for (int f = 0; f < model.surface_triangles.cols(); ++f)
    for (int k = 0; k < 3; ++k) on_surface[model.surface_triangles(k, f)] = 1;
  std::vector<int> nodes;
  for (int node = 0; node < model.num_nodes(); ++node)
    if (on_surface[node] && !model.dof_is_fixed[3 * node]) nodes.push_back(node);
  return nodes;
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
