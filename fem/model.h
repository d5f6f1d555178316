#pragma once
// fem::Model: everything about the deformable body that does not change while it moves (rest
// mesh, material, fixed degrees of freedom, lumped masses, per-tet rest data). Built once by
// MakeModel and then read-only; the moving part lives in fem::State.
//
// Degrees of freedom are node-major: dof 3n + a is axis a of node n. Positions and velocities
// are stacked 3N vectors; Eigen::Map them as (3 x N) when a matrix view reads better.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/eigen_types.h"
#include "fem/material.h"
#include "fem/quadratic_tet.h"
#include "fem/surface_embedding.h"
#include "fem/tet_mesh.h"

namespace hapsim::fem {

// Rest data of one linear tet. With D_m = [X1−X0, X2−X0, X3−X0] (rest edges), the deformation
// gradient is F = Σ_i x_i b_iᵀ, where b_1..3 are the rows of D_m⁻¹ and b_0 = −(b_1 + b_2 + b_3).
struct TetRestData {
  Eigen::Matrix<double, 3, 4> shape_gradients_1_m;  // columns b_0..b_3, 1/m
  double volume_m3 = 0.0;                           // V > 0
  // Lamé constants of the tet's material (one body may hold several objects, each its own).
  double lame_mu_Pa = 0.0;
  double lame_lambda_Pa = 0.0;
};

struct Model {
  TetMesh mesh;
  Matrix3Xi surface_triangles;  // (3 x F) outward-oriented boundary faces
  // The surface the tool's contacts are found on when it is not the boundary above: a finer or
  // smoother one carried by the tets (fem/surface_embedding.h). Empty: the boundary itself.
  EmbeddedSurface collision_surface;
  // The material: its Rayleigh damping (α, β) holds for every tet; its elastic constants and
  // density are the tets' for a body of one material (a merged body's tets keep their own, in
  // tet_rest and node_mass_kg; this is the first object's).
  Material material;
  // One per tet; for quadratic tets, its corner tet's (whose rotation is the element's).
  std::vector<TetRestData> tet_rest;
  // Quadratic tets only: each tet's stiffness K_e at rest (fem/quadratic_tet.h), over
  // mesh.node(0..9, t), its upper node-pair blocks packed (P2PackedStiffness, 3.96 kB a tet).
  // Empty for linear tets.
  std::vector<P2PackedStiffness> quadratic_stiffness;
  // (N) lumped mass: ρV/4 from each incident linear tet; a quadratic tet's HRZ masses (1/36 of
  // its ρV at a corner, 4/27 at an edge node for a straight one).
  Eigen::VectorXd node_mass_kg;
  Eigen::VectorXd dof_mass_kg;             // (3N) node_mass_kg repeated per axis
  std::vector<std::uint8_t> dof_is_fixed;  // (3N) 1 for a Dirichlet (fixed) dof
  // A body merged from several objects (MergeModels): the first node of each, ascending, from 0.
  // Empty: one object. The objects touch each other (contact/body_body_contacts.h).
  std::vector<int> object_first_nodes;
  Eigen::VectorXd rest_positions_m;        // (3N) stacked rest positions X

  int num_nodes() const { return mesh.num_nodes(); }
  int num_dofs() const { return 3 * mesh.num_nodes(); }
  int num_tets() const { return mesh.num_tets(); }
  bool is_quadratic() const { return mesh.is_quadratic(); }
  int num_fixed_nodes() const;
  // The objects of the body (MergeModels; 1 unless merged) and the nodes [first, end) of object o.
  int num_objects() const {
    return object_first_nodes.empty() ? 1 : static_cast<int>(object_first_nodes.size());
  }
  int object_first_node(int o) const {
    return object_first_nodes.empty() ? 0 : object_first_nodes[o];
  }
  int object_end_node(int o) const {
    return o + 1 < num_objects() ? object_first_nodes[o + 1] : num_nodes();
  }
};

// Builds the model. `fixed_nodes` lists nodes whose three dofs are fixed.
// Throws std::invalid_argument if the mesh fails FindRestMeshProblem or a node index is bad.
Model MakeModel(TetMesh mesh, const Material& material, const std::vector<int>& fixed_nodes);

// Several bodies as one (a scene's deformable objects): meshes side by side (nodes and tets of
// model k after those of models 0..k−1), each tet with its own Lamé constants, each node its mass
// and fixity. The objects do not touch each other through the FEM (their stiffness blocks are
// disjoint); they meet only through contacts. Throws std::invalid_argument if `models` is empty,
// their Rayleigh damping differs (one damping serves the implicit step's matrix) or they mix
// linear and quadratic tets.
Model MergeModels(const std::vector<Model>& models);

// Nodes whose rest position lies in the axis-aligned box [min_m − tol, max_m + tol].
// The nodes of model.surface_triangles that are not fixed, ascending: the surface points that can
// move, so that a contact or grasp row on one has a non-zero compliance (W_ii > 0).
std::vector<int> FindFreeSurfaceNodes(const Model& model);

std::vector<int> FindNodesInBox(const TetMesh& mesh, const Eigen::Vector3d& min_m,
                                const Eigen::Vector3d& max_m, double tolerance_m);

}  // namespace hapsim::fem
