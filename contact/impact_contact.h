#pragma once
// Impact with restitution (paper 001: the unilateral surface constraint's Lagrange multipliers,
// projected onto the contact normals, give the impulse of an impact that obeys a coefficient of
// restitution e), on the haptic tool's contacts at 1 kHz (contact/haptic_contact_finder.h).
//
// The tool's step (core/tool_integrator.h) with contact forces λ_i ≥ 0 along a_i = −n_i (n out of
// the tool) at the points r_i from its centre of mass:
//   A_v Δv = Δt (F̃ + Σ a_i λ_i),   A_L ΔL = Δt (T̃ + Σ (r_i × a_i) λ_i),   ω⁺ = M⁻¹ L⁺.
// The rate at which contact i separates is s_i = a_i·v + (r_i × a_i)·ω, so after the step
//   s⁺ = s_free + W λ,   W_ij = Δt (a_iᵀ A_v⁻¹ a_j + (r_i × a_i)ᵀ M⁻¹ A_L⁻¹ (r_j × a_j)),
// and λ solves the complementarity problem s⁺_i ≥ target_i ⊥ λ_i ≥ 0 (projected Gauss–Seidel;
// W is the tool's Delassus matrix, a few rows). The targets are Newton's law of restitution
// for a contact that closes within this step:
//   impact    (s_i < −v_rest and gap_i + s_free,i Δt ≤ 0):  s⁺_i ≥ −e s_i
//   otherwise (resting, or not closing within the step):   s⁺_i ≥ −gap_i/Δt
// (the second lets a contact close exactly its gap in the step: resting contact, and no early
// bounce of a contact still a step away). Velocities are those at the step's start (s_i) and of
// the collision-free step (s_free). An impact is resolved at the step it would cross, from up to
// |s| Δt above the surface: the rebound's apex is off by at most (1 + e²)|s| Δt.
// The tool is rigid against rigid objects (and the last frame's body surface, as rigid).

#include <Eigen/Core>
#include <vector>

#include "contact/contact.h"
#include "core/rigid_tool.h"
#include "core/tool_integrator.h"

namespace hapsim::contact {

struct ImpactParams {
  double restitution = 0.5;      // e in [0, 1]
  double rest_speed_m_s = 1e-3;  // approach slower than this is resting contact (no bounce)
  int max_contacts = 64;         // rows solved (the deepest ones when there are more)
  int max_iterations = 100;      // Gauss–Seidel sweeps
  double tolerance_m_s = 1e-9;   // stop when no target is missed by more than this
};

class ImpactContact {
 public:
  // Throws std::invalid_argument for e outside [0, 1], v_rest < 0, max_contacts < 1,
  // max_iterations < 1 or a negative tolerance.
  explicit ImpactContact(const ImpactParams& params);

  // The contact force and torque on the tool (world; torque about the tool's centre of mass)
  // over the step whose free system is `system`, at tool state `tool`. Allocates nothing (up to
  // 4,096 contacts; more: the depth ordering grows once).
  void Calc(const std::vector<Contact>& contacts, const ToolStepSystem& system,
            const ToolModel& model, const ToolState& tool, Eigen::Vector3d* F_W_N,
            Eigen::Vector3d* T_W_N_m);

  int num_rows() const { return n_; }
  int num_impacts() const { return num_impacts_; }  // rows of the last Calc with a bounce target
  const ImpactParams& params() const { return params_; }

 private:
  void SolveRows();  // λ for the rows set up by Calc

  ImpactParams params_;
  int n_ = 0;
  int num_impacts_ = 0;
  Eigen::Matrix3Xd a_, ra_;   // (3 x max) a_i and r_i × a_i
  Eigen::Matrix3Xd gv_, gw_;  // (3 x max) A_v⁻¹ a_j and M⁻¹ A_L⁻¹ (r_j × a_j)
  Eigen::MatrixXd W_;         // (max x max)
  Eigen::VectorXd s_, target_, lambda_;
  std::vector<int> order_;  // contacts by depth, when there are more than max_contacts
};

}  // namespace hapsim::contact
