#pragma once
// The visual frame's friction solve (SolveContactImpulses with ContactLaw::kFriction and
// FrictionMethod::kWorkingSet; issue 25 item 2). The problem is contact_solver.h's: with
// c = Δt W λ − rhs, per contact
//
//   0 ≤ λ_n ⟂ c_n ≥ 0,   |λ_t| ≤ μ λ_n,   c_t = 0 inside the disc, λ_t opposite c_t on its rim,
//
// W (3m × 3m for m contacts; dense, not necessarily symmetric) = J_v A_v⁻¹ J_vᵀ + J_ω M⁻¹A_L⁻¹ J_ωᵀ
// + J_u A_u⁻¹ J_uᵀ (DESIGN.md §4). It stops on the dense projected Gauss–Seidel's test
// (FrictionMethod::kDenseGaussSeidel): CalcFrictionResidual ≤ tolerance, whose zero is Coulomb's
// law, so both return the same λ to within the tolerance (tests/contact/frame_friction_test.cc).
// What differs is the work to get there:
//
//  1. A working set. Of up to 240 candidates on block_press_friction ~180 approach at λ = 0 and
//     ~70 end up carrying load. Only contacts with λ ≠ 0 or c_n < 0 at the start are swept, on a
//     contiguous copy M = Δt W_SS of their rows; c_S is kept by columns (a change δ of contact
//     j's impulses costs c_S += M[:, j] δ, O(|S|), as the 1 kHz solver's AddContactColumns).
//     Contacts separated (λ = 0, c_n ≥ 0) for 3 sweeps in a row are dropped once they are a
//     quarter of the set. When the set is solved the others' velocities c_O = Δt W_OS λ_S − rhs_O
//     are formed once; any that approaches (normal residual above the tolerance) joins and the
//     set is solved again. The others then meet the law exactly (λ = 0, c_n ≥ 0).
//  2. The sweep is SolveContactImpulses' blocked projected Gauss–Seidel (normal row, then the
//     tangent pair by StepTangentialImpulse). On its own it converges linearly and slowly here:
//     a flat tool pressed into a soft block makes W nearly singular along smooth load
//     distributions, and the dense solver needed ~1,700 sweeps to reach 1e-12 in the press
//     (500, its cap, left a residual of up to 2e-5 on 33 of the 100 frames).
//  3. Newton steps. Once no contact changes state (separated, sticking, sliding) for 4 sweeps,
//     the loaded contacts' equations with their states held,
//       sticking:  c_n = 0, c_t = 0
//       sliding:   c_n = 0, |λ_t| = μλ_n, c_t1 λ_t2 − c_t2 λ_t1 = 0  (c_t ∥ λ_t)
//       μ = 0:     c_n = 0, λ_t = 0
//     are solved by a Newton step (LU of the 3 n_loaded square Jacobian), followed by a sweep,
//     which projects the iterate back into the admissible set and re-classifies the contacts.
//     The step is kept if it lowers the residual, else undone (and the next attempt waits twice
//     as many stable sweeps). While the loaded contacts and their states stay the same, the next
//     steps reuse the factor (chord steps, O(n²)); one that does not lower the residual is
//     redone with a fresh factor. The sweeps only select the states and keep every returned
//     iterate admissible (λ_n ≥ 0, |λ_t| ≤ μλ_n); the Newton steps take the residual from ~1e-2
//     to 1e-13 in a few steps.
//  4. The residual is evaluated from the kept c_S (O(|S|) per sweep, not a product with W) and
//     confirmed on c_S recomputed from M before the solve ends, so round-off in the kept sums
//     cannot end it early.
//
// Measured on the 76 loaded frames of block_press_friction (their problems dumped from `hapsim
// sim --mode lcp` with a temporary hook, solved by a hand-built driver; 2026-11-26 23:55 UTC,
// AMD EPYC, host shared with a build): 46 sweeps, 7.6 Newton steps tried and ~1.6 LU
// factorisations (LAPACK dgetrf, ~210 rows) a solve, 1.4–1.6 ms mean; the dense solver took
// 47–120 ms on four of them (500 sweeps, its cap, on two). In `hapsim sim` the frame's median
// went from 65–89 ms to 12–14 ms on that host (runs alternated within minutes).
// report.iterations counts sweeps (≤ options.max_iterations, those after Newton steps
// included); report.newton_steps the steps tried.

#include <Eigen/Core>

#include "contact/contact_solver.h"

namespace hapsim::contact {

// Solves the friction law as above. W (rows × rows), rhs (rows), rows a multiple of 3 (normal,
// t1, t2 per contact, contact_jacobian.h); mu ≥ 0 per contact (size rows / 3). On entry *lambda
// is the start (zero if its size is wrong; clamped to be admissible); on return the solution, or
// the last admissible iterate if options.max_iterations sweeps did not reach options.tolerance.
// report.residual is CalcFrictionResidual's measure of the returned λ (up to round-off in c).
// A contact whose normal compliance W_nn is not positive cannot be stepped: it keeps λ = 0 and,
// if it approaches, the solve does not converge. Throws std::invalid_argument on inconsistent
// sizes.
ContactSolveReport SolveFrictionOnWorkingSet(const Eigen::MatrixXd& W, const Eigen::VectorXd& rhs,
                                             double dt_s, const Eigen::VectorXd& mu,
                                             const ContactSolveOptions& options,
                                             Eigen::VectorXd* lambda);

}  // namespace hapsim::contact
