#pragma once
// Coulomb friction in the 1 kHz solve of the `lcp` mode (issue 13). The visual frame hands over
// three rows per contact (normal n, tangents t1, t2; contact_jacobian.h) frozen at the frame,
// with each contact's friction coefficient μ_i (ContactRows with rows_per_contact 3). At every
// haptic step, with the tool's step system and the discrete-time wrench F̂, T̂ as in the
// frictionless solve (haptic_lcp_solver.h),
//
//   c = Δt W λ − rhs,   W = W_body + U S Uᵀ,   rhs = body_rhs − U s_free
//   U = [J_v J_ω] (n × 6),   S = blockdiag(A_v⁻¹, M⁻¹A_L⁻¹),   s_free = S Δt [F̂; T̂]
//
// and per contact, Coulomb's law with the disc:
//
//   0 ≤ λ_n ⟂ c_n ≥ 0,   |λ_t| ≤ μ λ_n,   c_t = 0 when |λ_t| < μ λ_n (stick),
//   λ_t = −μ λ_n c_t / |c_t| otherwise (slide: friction opposes the tangential velocity).
//
// The force on the tool is F_c = J_vᵀλ, the torque T_c = J_ωᵀλ. λ_n ≥ 0 in every iterate, so the
// solve never pulls the tool, converged or not.
//
// Method: blocked projected Gauss–Seidel over the contacts, the same sweep and fixed point as
// SolveContactImpulses' kFriction (contact_solver.h), so that the two agree to the tolerance.
// W (n × n, dense) is never formed. The solver keeps y = W_body λ and g = Uᵀλ; a contact's local
// velocity is c_i = Δt (y_i + U_i S g) − rhs_i (O(1) per contact), and a change δ of a contact's
// three impulses costs y += W_body[:, i] δ (3 per coupled row, ContactRows::num_uncoupled_rows;
// 9 for an uncoupled contact) and g += U_iᵀ δ. A contact that stays separated (λ_i = 0,
// c_n ≥ 0) costs its normal velocity alone (its 3 × 3 block of W is formed only for contacts
// that carry load or are about to), so a sweep costs ~3 n_coupled per contact that carries load
// plus ~10 flops per separated one. A contact whose tangential block of W is not positive
// carries no friction (StepTangentialImpulse); one whose normal compliance is not positive fails
// the solve once a sweep reaches it.
//
// Warm start: the previous step's λ with the same rows (compared bitwise, as HapticLcpSolver
// does), y and g kept; new rows start from the frame's impulses (ContactRows::lambda_frame_N, the
// visual frame's own friction solve) or zero. A step does sweeps until no impulse moves by more
// than kTolerance of the largest, or max_sweeps: the haptic step's time is bounded. An iterate
// cut off by max_sweeps is still admissible (λ_n ≥ 0, |λ_t| ≤ μλ_n); its distance from the law
// is last_residual(), and the next step continues from it.
//
// No heap allocation after construction (tests/contact/haptic_friction_test.cc, 510 rows).
//
// Cost (tests/bench/haptic_friction_benchmark.cc; 2.6 GHz EPYC, SSE2 Release; a soft body pressed
// so that most contacts carry load, μ 0.5, F̂ moved ~0.01 N a step): a warm step of 1 / 5 / 20
// sweeps takes 6.8 / 17 / 56 µs at 25 contacts, 26 / 62 / 204 µs at 70 and 149 / 330 / 1094 µs
// at 200 (146 carrying load, 600 rows), leaving a Coulomb residual of ~4e-4 / 4e-5 / 1e-6 of the
// largest impulse. At 200 contacts a sweep is ~45 µs (W_body is 2.9 MB, past the L2 cache).
// (Since then rows carry a stamp, so that the bitwise comparison of ~45 µs more is gone, and the
// frame couples only the contacts the tool may reach: tests/bench/haptic_step_benchmark.cc's
// BM_HapticFrictionStep has the step on block_press_friction's own rows.)

#include <Eigen/Core>
#include <memory>

#include "contact/haptic_contact_rows.h"
#include "core/tool_integrator.h"

namespace hapsim::contact {

class HapticFrictionSolver {
 public:
  // A sweep moving no impulse by more than this times the largest one ends the solve.
  static constexpr double kTolerance = 1e-12;

  // Preallocates everything for up to max_rows rows (memory ≈ 8 max_rows² bytes); each Solve
  // does at most max_sweeps sweeps. Throws std::invalid_argument if max_rows < 0 or
  // max_sweeps < 1.
  HapticFrictionSolver(int max_rows, int max_sweeps);
  ~HapticFrictionSolver();
  HapticFrictionSolver(HapticFrictionSolver&&) noexcept;
  HapticFrictionSolver& operator=(HapticFrictionSolver&&) noexcept;

  // Solves for `rows` (rows_per_contact 3), the tool system `tool` of this step and F̂, T̂
  // (world, N and N m), and writes F_c = J_vᵀλ (N) and T_c = J_ωᵀλ (N m, about the tool's COM),
  // world. Returns false, with zero force and torque, if the rows are not friction rows, exceed
  // max_rows(), are inconsistent in size, not finite, W_body is not symmetric, a contact's
  // normal has no positive compliance, or the iterate stopped being finite; never allocates,
  // never throws.
  bool Solve(const ContactRows& rows, const ToolStepSystem& tool, const Eigen::Vector3d& F_hat_N,
             const Eigen::Vector3d& T_hat_N_m, Eigen::Vector3d* F_c_N, Eigen::Vector3d* T_c_N_m);

  // Copies and checks new rows and sets up the warm start (y = W_body λ_frame, an O(n_c² + n)
  // product) ahead of time, off the 1 kHz loop; the following Solve on the same rows starts warm.
  // Returns false for rows Solve would reject (leaving no rows cached: the next Solve copies
  // afresh). Allocates nothing.
  bool Prepare(const ContactRows& rows);

  int max_rows() const;
  int max_sweeps() const;
  // Sweeps done by the last Solve.
  int last_iterations() const { return last_iterations_; }
  // CalcFrictionResidual of the last Solve's λ (contact_solver.h): 0 exactly on Coulomb's law.
  double last_residual() const { return last_residual_; }
  // Contacts with λ_n > 0 after the last Solve.
  int last_num_active() const { return last_num_active_; }
  // Contacts among those whose friction is on the rim of its disc (sliding) after the last Solve.
  int last_num_sliding() const { return last_num_sliding_; }
  // λ per row after the last successful Solve (size num_rows), N.
  Eigen::Ref<const Eigen::VectorXd> last_impulses() const;

 private:
  struct Workspace;
  std::unique_ptr<Workspace> ws_;
  int last_iterations_ = 0;
  double last_residual_ = 0.0;
  int last_num_active_ = 0;
  int last_num_sliding_ = 0;
};

}  // namespace hapsim::contact
