#pragma once
// The unilateral contact solve of the haptic step in the `lcp` mode (DESIGN.md §4: "with
// unilateral contacts the haptic process can instead receive the per-contact rows and solve the
// small LCP at 1 kHz"). The visual frame hands over the constraint rows frozen at the frame
// (ContactRows, haptic_contact_rows.h); at every haptic step, with the tool's step system and
// the discrete-time force and torque F̂, T̂, the haptic process solves
//
//   W = J_v A_v⁻¹ J_vᵀ + J_ω M⁻¹ A_L⁻¹ J_ωᵀ + W_body                      (n × n)
//   v_free = A_v⁻¹ Δt F̂,   ω_free = M⁻¹ A_L⁻¹ Δt T̂                         (free tool velocities)
//   rhs = body_rhs − J_v v_free − J_ω ω_free          (= b − c_free, c_free = J_v v_free +
//                                                        J_ω ω_free + J_u u̇)
//   c = Δt W λ − rhs ≥ 0,   λ ≥ 0,   cᵀλ = 0                               (Signorini LCP)
//
// and returns F_c = J_vᵀλ, T_c = J_ωᵀλ. With every contact active this is the equality solve
// of the linear contact model (linear_contact_model.h), which it reproduces; unlike that model
// it lets contacts separate (and re-engage) between visual frames.
//
// Algorithm (see HapticLcpSolver). The tool part of W has rank ≤ 6 and the body part is frozen
// for the frame, so W(t) = W̄ + U ΔS(t) Uᵀ with U = [J_v J_ω] (n × 6), S = blockdiag(A_v⁻¹,
// M⁻¹A_L⁻¹), W̄ = W_body + U S̄ Uᵀ for a symmetric positive definite S̄ fixed when the rows
// arrive, ΔS = S − S̄. A primal active-set method (Lawson & Hanson's NNLS in its QP form, as
// SolveContactImpulses' kUnilateral) is run with every equality solve on the active set done by
// the Schur-complement method of active-set QP solvers (Gill, Murray, Saunders & Wright 1990;
// Bartlett & Biegler's QPSchur 2006): one dense Cholesky factor of a base block W̄_BB, kept
// while the rows stay the same, and a small dense border for the rank-6 tool change and the
// rows that entered or left the active set since. Warm-started from the previous step's active
// set, a haptic step with unchanged rows and contacts costs O(n_c² + n) for the complementarity
// check (n_c the rows that couple through W_body, ContactRows::num_uncoupled_rows; the others
// only through the tool) plus O(n·m + m³), m ≤ 6 + 32 border columns, and no factorisation of
// an n × n matrix.

#include <Eigen/Core>
#include <memory>

#include "contact/haptic_contact_rows.h"
#include "contact/haptic_friction_solver.h"
#include "core/tool_integrator.h"

namespace hapsim::contact {

// The LCP above, exactly (to round-off; within a step's budget of equality solves when one is
// set, see the constructor), at 1 kHz and without heap allocation after construction.
//
// Caching and warm start. The solver keeps a copy of the last rows it was given and compares
// each call's rows with it bitwise (memcmp, ~2 µs at n = 125). Unchanged rows (the haptic steps
// within a visual frame) keep the base factorisation, the border and the previous step's active
// set. Changed rows (a new frame: other contacts, whose indices say nothing about the old set)
// are copied, checked and factorised once, starting from the frame's active set
// (ContactRows::lambda_frame_N > 0) or, without it, from the rows that ask for a push,
// rhs_i > 0. The guess only decides how much work is done, never the answer (held rows, below,
// are another matter: their set is the frame's): the set is first
// shrunk until its equality solution is positive, then the active-set iteration runs to
// complementarity; the LCP has a unique solution whenever W's symmetric part is positive
// definite, so every guess reaches the same λ.
//
// Contracts: W_body symmetric (its lower triangle is read; an asymmetry above 1e-9 of its
// largest entry is rejected) and positive semidefinite, A_v and A_L invertible, Δt > 0. A set
// of rows whose W is singular (more independent constraints than the tool's 6 plus the body's
// rank) has no unique solution; the solver then reports failure rather than guessing. Singular
// here is to working precision: a base pivot at most 1e-10 of its diagonal (haptic_lcp_solver.cc
// FactorCholeskyInPlace); held rows found so are solved unilaterally instead.
//
// Cost (tests/bench/haptic_lcp_benchmark.cc; 2.6 GHz EPYC, this SSE2 Release build, n = 25 /
// 50 / 125 rows): a warm step 1.9 / 3.2 / 9.8 µs (no factorisation); the first step of a frame
// whose rows are its active contacts 7 / 20 / 117 µs (one Cholesky factorisation, 65 µs of it
// at 125); with ~20% of the rows separating at once 10 / 38 / 234 µs (two). For comparison a
// single dense LU of W costs 2.3 / 11 / 118 µs and the paper's linear model 7 ns. A solve whose
// residual exceeds 1e-9 (round-off in a long border; not observed in testing) is redone once
// from a fresh factorisation.
//
// No heap allocation after construction, checked by tests/contact/haptic_lcp_test.cc up to 512
// rows with over 300 active (the base block is factorised by matrix–vector products: Eigen's
// blocked Cholesky took its GEMM scratch from the heap from ~400 active rows on).
//
// Held rows (the `hybrid` haptic mode, issue 25). Built with hold_frame_contacts, the solver
// holds the frame's active rows (ContactRows::lambda_frame_N > 0) as equalities, as the paper's
// linear contact model does (its λ of either sign, c_i = 0), and switches the frame's other rows
// on and off unilaterally: the mixed LCP
//   c_H = 0 (λ_H free),   c_F ≥ 0, λ_F ≥ 0, c_Fᵀλ_F = 0,   c = Δt W λ − rhs,
// which, while no other row engages, is exactly the linear contact model's equality solve on the
// same rows (with this step's tool system in place of the frame's), and stops a tool that reaches
// a row the frame did not find active (the linear model alone lets it through). The same
// active-set iteration solves it: held rows are never dropped and never tested for sign (a convex
// QP in which they are unconstrained; W's symmetric part positive definite keeps it unique), but
// one whose pull exceeds its frame impulse (λ_i < −λ_frame,i: held against a near-twin free row,
// haptic_lcp_solver.cc ReleaseRowsPullingPastTheirPush) is released, solved unilaterally from
// then on until new rows come.
// Dependent held rows (W_HH singular: redundant contacts the frame found active, which its own
// solve admits through a small diagonal shift) are not held: those rows are then solved
// unilaterally, as in the lcp mode, until new rows come. (The linear model factorises such a W by
// a complete orthogonal decomposition; the fall-back to it would lose the rows a fast tool meets.)
//
// A grasp's rows (ContactRows::num_bilateral_rows, the leading rows; contact/tissue_grasp.h) are
// held in every mode, with or without hold_frame_contacts, and never released: the bilateral
// rows of the mixed LCP above, whose pull the device feels between frames. Dependent grasp rows
// (W singular on them) fail the solve rather than be solved unilaterally: the step then renders
// the linear contact model, which holds them.
//
// Friction rows (ContactRows::rows_per_contact 3, the friction law) go to a HapticFrictionSolver
// the solver owns when built with friction_sweeps > 0 (its sweep budget per step); the counters
// below then describe that solve (iterations are sweeps, no factorisations).
class HapticLcpSolver {
 public:
  // Preallocates everything for up to max_rows rows (memory ≈ 16 max_rows² bytes, and 8 max_rows²
  // more with friction_sweeps > 0). hold_frame_contacts: the frame's active rows are held as
  // equalities (above; normal rows only, friction rows are solved as without it). Throws
  // std::invalid_argument if max_rows < 0 or friction_sweeps < 0.
  //
  // max_solves_per_step > 0 bounds a Solve's work (issue 25: a trainer session's 1 kHz step once
  // took 1.8 ms, 127 equality solves on 259 new rows): a Solve that has done that many equality
  // solves stops at the top of the next active-set iteration and returns its iterate, which is
  // feasible (λ ≥ 0 off the held rows) and optimal on its active set, only not yet complementary:
  // rows still to enter do not push yet. The next Solve on the same rows goes on from that set,
  // so a few steps reach the solution the unbounded solve would give in one. Counted in solves,
  // not time, so that runs replay bit for bit. 0: unbounded (3n + 10 entering rows at most). A
  // release of held rows (above) goes past the budget by the pass that drops their negative
  // impulses (ShrinkToFeasible: a few solves), so that no step returns a pulling released row.
  explicit HapticLcpSolver(int max_rows, int friction_sweeps = 0, bool hold_frame_contacts = false,
                           int max_solves_per_step = 0);
  ~HapticLcpSolver();
  HapticLcpSolver(HapticLcpSolver&&) noexcept;
  HapticLcpSolver& operator=(HapticLcpSolver&&) noexcept;

  // Solves the LCP for `rows`, the tool system `tool` of this haptic step (A_v, A_L, M⁻¹, Δt)
  // and F̂, T̂ (world, N and N m, CalcDiscreteTimeWrench), and writes F_c = J_vᵀλ (N) and
  // T_c = J_ωᵀλ (N m, about the tool's COM), world. Returns false, with zero force and torque,
  // if rows.num_rows() > max_rows(), the rows are friction rows and the solver has no friction
  // solve, are inconsistent in size (HasConsistentShape), not finite or
  // W_body not symmetric, or the active-set iteration failed (singular W, no convergence within
  // 3n + 10 entering or refused rows, or a complementarity residual past 1e-2 after its retry);
  // never allocates, never throws. With max_solves_per_step, a call may return true before
  // complementarity: last_out_of_budget() says so, and its λ is feasible.
  //
  // targets, if given (≥ num_rows entries, the first num_rows read): this step's b − body
  // velocity per row in place of rows.body_rhs, for a caller whose targets move between frames
  // (the hybrid mode's free rows follow the tool, device/haptic_step.h). A step whose targets
  // differ from the last one's costs one more forward substitution, O(k0²), and no factorisation.
  // Non-finite targets fail the solve. Normal rows only (friction rows ignore them).
  bool Solve(const ContactRows& rows, const ToolStepSystem& tool, const Eigen::Vector3d& F_hat_N,
             const Eigen::Vector3d& T_hat_N_m, Eigen::Vector3d* F_c_N, Eigen::Vector3d* T_c_N_m,
             const Eigen::VectorXd* targets = nullptr);

  // Does the work of the first Solve on new rows ahead of time, off the 1 kHz loop (the visual
  // frame, or the haptic process's receive thread): copies and checks the rows, guesses the
  // frame's active set (or the rows that ask for a push) and factorises its base block with S̄
  // from `tool` (the tool system at linearisation: any symmetric positive definite S̄ is exact;
  // the first Solve borders the difference to its own). A following Solve on the same rows then
  // takes the warm path. Returns false, leaving nothing prepared, for rows Solve would reject.
  // Not concurrent with Solve on the same solver; allocates nothing.
  bool Prepare(const ContactRows& rows, const ToolStepSystem& tool);

  int max_rows() const;
  // The friction solve's sweep budget per step; 0: friction rows are refused.
  int friction_sweeps() const;
  bool hold_frame_contacts() const { return hold_frame_contacts_; }
  // Equality solves on an active set in the last Solve (1 when the warm start was right).
  int last_iterations() const { return last_iterations_; }
  // max_i |min(λ_i, c_i/(Δt W_ii))| / max_i λ_i (absolute when λ = 0), the measure of
  // ContactSolveReport::residual, with |c_i/(Δt W_ii)| for a held row; ≲ 1e-12 when converged.
  double last_residual() const { return last_residual_; }
  // Rows with λ ≠ 0 after the last Solve (a held row may pull: λ < 0).
  int last_num_active() const { return last_num_active_; }
  // Dense Cholesky factorisations of a base block in the last Solve: 0 at a warm step with the
  // same rows, ≥ 1 when the rows changed or the border of changes grew past its capacity.
  int last_num_factorizations() const { return last_num_factorizations_; }
  // The last Solve stopped at max_solves_per_step before complementarity (its λ is feasible).
  bool last_out_of_budget() const { return last_out_of_budget_; }
  int max_solves_per_step() const { return max_solves_per_step_; }
  // λ per row after the last Solve (size num_rows), N; empty when it failed.
  Eigen::Ref<const Eigen::VectorXd> last_impulses() const;

 private:
  struct Workspace;
  // The active-set iteration, redone once from a fresh factorisation should round-off have spoilt
  // its complementarity (Solve); sets last_out_of_budget_ and last_residual_. False: failed.
  bool RunActiveSetWithRetry(double dt_s, double tolerance);

  std::unique_ptr<Workspace> ws_;
  std::unique_ptr<HapticFrictionSolver> friction_;  // null without friction sweeps
  bool hold_frame_contacts_ = false;
  int max_solves_per_step_ = 0;
  bool last_out_of_budget_ = false;
  bool last_was_friction_ = false;
  bool last_solved_ = false;
  int last_iterations_ = 0;
  double last_residual_ = 0.0;
  int last_num_active_ = 0;
  int last_num_factorizations_ = 0;
};

}  // namespace hapsim::contact
