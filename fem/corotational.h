#pragma once
// Corotational linear elasticity on linear tets (Müller & Gross 2004; DESIGN.md §2).
//
// Per tet e with rotation R_e of its deformation gradient F = Σ_i x_i b_iᵀ:
//   small strain in the rotated frame   ε = sym(R_eᵀ F − I)
//   stress (isotropic linear)           σ = 2μ ε + λ tr(ε) I
//   elastic force on node i             f_i = −V R_e σ b_i     ( = −R_e K_e (R_eᵀ x_e − X_e) )
//   energy                              E_e = V (μ ε:ε + λ/2 tr(ε)²)
// With R_e = I this is plain linear FEM, whose force is not invariant under rotation.
// Quadratic tets (fem/quadratic_tet.h) take R_e from their corner tet, as here, and their force
// f_e = −R_e K_e (R_eᵀ x_e − X_e) and energy from the stored K_e. CalcElementStress is the corner
// tet's (the mean strain of a straight quadratic tet is not its corners'; for display only).

#include <Eigen/Core>
#include <vector>

#include "fem/fem_options.h"
#include "fem/model.h"

namespace hapsim::fem {

// R_e for every tet at positions x_m (3N): the rotation of F_e (CalcRotationsOfDeformation, many
// tets at a time), or I for kLinear.
// `rotations` must have num_tets() entries (resized if not).
void CalcElementRotations(const Model& model, const Eigen::VectorXd& x_m, ElasticityKind kind,
                          std::vector<Eigen::Matrix3d>* rotations);

// Elastic force f = −∂E/∂x (3N, N) at x_m with the rotations held fixed. Overwrites *force_N.
void CalcElasticForce(const Model& model, const Eigen::VectorXd& x_m,
                      const std::vector<Eigen::Matrix3d>& rotations, Eigen::VectorXd* force_N);

// Total elastic energy Σ_e E_e, J.
double CalcElasticEnergy(const Model& model, const Eigen::VectorXd& x_m,
                         const std::vector<Eigen::Matrix3d>& rotations);

// Per-tet Cauchy-like small-strain stress σ in the rotated frame (σ_e as above), Pa.
Eigen::Matrix3d CalcElementStress(const Model& model, const Eigen::VectorXd& x_m,
                                  const Eigen::Matrix3d& rotation, int tet);

}  // namespace hapsim::fem
