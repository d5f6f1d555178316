#pragma once
// Average nodal pressure on linear tets (`element: p1_nodal_pressure`; Bonet & Burton, "A simple
// average nodal pressure tetrahedral element for incompressible and nearly incompressible dynamic
// explicit applications", Commun. Numer. Meth. Engng 14, 1998), in hapsim's small-strain
// corotational form: a remedy for the locking of linear tets at tissue-like Poisson ratios
// (issue 27 item 4).
//
// A linear tet has one volumetric strain θ_e = tr ε_e; near incompressibility each tet must then
// keep its own volume, more constraints than a tet mesh has freedoms, and it locks. Here the
// energy keeps each tet's deviatoric part and takes the volumetric part at the nodes, from the
// volumetric strain averaged over each node's tets:
//
//   θ_e = tr(R_eᵀ F_e − I) = Σ_a b_a·(R_eᵀ x_a) − 3,      θ_n = Σ_{e∋n} (V_e/4) θ_e / V_n,
//   E = Σ_e V_e μ dev ε_e : dev ε_e  +  Σ_n V_n (κ_n/2) θ_n²,       κ = λ + 2μ/3,
//
// about as many volume constraints as nodes, not tets. With the rotations held fixed its force on
// node a is that of a tet stress with the nodal pressures averaged back over the tet,
//
//   f_a = −Σ_{e∋a} V_e R_e σ̄_e b_a,   σ̄_e = 2μ dev ε_e + p̄_e I,   p̄_e = ¼ Σ_{n∈e} κ_n θ_n,
//
// and its stiffness the deviatoric tet blocks (λ replaced by −2μ/3) plus, per node,
//
//   K_vol = Σ_n κ_n V_n g_n g_nᵀ,   g_n = ∂θ_n/∂x = Σ_{e∋n} (V_e/(4 V_n)) R_e b^e,
//
// which couples every pair of nodes of n's tets: a wider pattern than the tets' own (the stiffness
// assembler adds it; fem/stiffness_assembly.h). A uniform strain gives θ_n = θ_e everywhere: the
// same force as the plain tet (the patch test), and a rigid motion none.

#include <Eigen/Core>
#include <vector>

#include "fem/model.h"

namespace hapsim::fem {

// Sets model->nodal_pressure from its tets (their volumes and Lamé constants). Throws
// std::invalid_argument for quadratic tets (which do not lock: fem/quadratic_tet.h).
void EnableNodalPressure(Model* model);

// p̄_e, the nodal pressures κ_n θ_n averaged over each tet (num_tets entries, Pa), at positions
// x_m with the rotations given. *node_strain is scratch (resized to num_nodes).
void CalcAveragedNodalPressures(const Model& model, const Eigen::VectorXd& x_m,
                                const std::vector<Eigen::Matrix3d>& rotations,
                                Eigen::VectorXd* node_strain, Eigen::VectorXd* element_pressure_Pa);

// Σ_n V_n (κ_n/2) θ_n², J.
double CalcNodalVolumetricEnergy(const Model& model, const Eigen::VectorXd& x_m,
                                 const std::vector<Eigen::Matrix3d>& rotations);

}  // namespace hapsim::fem
