#pragma once
// Contact impulses from the Delassus matrix (DESIGN.md §4), three laws behind one function:
//
//   equality   (the paper)  Δt (W + ε diag W) λ = b − c_free             dense, rank-revealing
//   unilateral (Signorini)  c = c_free − b + Δt W λ ≥ 0, λ ≥ 0, cᵀλ = 0  primal active set
//   friction   (Coulomb)    normal rows as unilateral; per contact the tangential impulse in the
//                           disc |λ_t| ≤ μ λ_n, opposite the slip on its rim: blocked projected
//                           Gauss–Seidel on a working set with Newton steps
//                           (frame_friction_solver.h), or over the dense W (FrictionMethod)
//
// W is (rows x rows) with W = J_v A_v⁻¹ J_vᵀ + J_ω M⁻¹ A_L⁻¹ J_ωᵀ + J_u A_u⁻¹ J_uᵀ. It is symmetric
// only when the coupling's torque Jacobian is (zero rotation error), and singular when contacts are
// redundant, so the equality solve uses a complete orthogonal decomposition rather than LDLᵀ. `rhs`
// = b − c_free, with b the position stabilisation −β φ/Δt plus any restitution target.
//
// Why the equality law has a compliance ε W_ii in series with each row (ε 1e-4 by default; the
// linear contact model built for the haptic step holds the same law, contact/visual_frame_model.cc):
// rows that are nearly, not exactly, redundant, such as the tool's rim points on faces whose nodes
// are held by rows of their own. W's condition number on block_press's frames runs 10⁸ to 10¹⁵
// (these figures: hand runs with a temporary print, 2026-11-29; the release map is the bench's).
// The exact solve (ε = 0) answers with large row forces of both signs that nearly cancel: pressed
// 5 mm at 100 Hz, the largest row force of a frame had a median of 308 N on the linear body and
// 1,190 N on the quadratic one, for a net force of 3.3 N; with the compliance, 0.68 N and 0.47 N.
// On the quadratic body the cancelling was not exact enough: the tool sank 0.24 mm further than
// under the unilateral law, left 0.8 mm penetrations, and the release map's equality cells stuck
// at 50 to 200 Hz (the map then ran each cell at one phase of the frame clock; since e90dff0 at
// its worst of eight). A row alone keeps its force up to the factor 1/(1 + ε); a pair of rows
// nearly one (W ≈ w[[1, 1 − η], [1 − η, 1]], η ≪ ε) keeps their sum so and splits it by their
// difference of rhs over Δt ε w instead of Δt η w. On the one-phase release map (ε then scaled by
// the mean diagonal, first tried) ε 1e-5 still left P2's equality cell at 20 Hz 40 mN stickier
// than at 1e-4; 1e-4 and 1e-3 agreed within 6 mN. ε = 0 is the exact solve. (The unilateral
// solve's diagonal shift, DelassusColumns in contact_solver.cc, is another thing: 1e-10 of the
// largest entry, only to keep its free-set systems nonsingular; it does not damp a nearly singular
// W's near-null direction.)

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

#include "contact/contact_jacobian.h"

namespace hapsim::contact {

enum class ContactLaw { kEquality, kUnilateral, kFriction };
const char* ToString(ContactLaw law);  // "equality", "unilateral", "friction"

// How kFriction is solved; both stop on the same residual (CalcFrictionResidual ≤ tolerance):
//   kWorkingSet        sweeps on the contacts that carry load or approach, W applied by columns,
//                      and Newton steps once their states settle (frame_friction_solver.h)
//   kDenseGaussSeidel  blocked projected Gauss–Seidel over every row of the dense W (the original
//                      solver: each sweep and each residual a product with the whole W)
enum class FrictionMethod { kWorkingSet, kDenseGaussSeidel };

struct ContactSolveOptions {
  ContactLaw law = ContactLaw::kUnilateral;
  double friction_coefficient = 0.0;  // μ ≥ 0, kFriction only
  // kFriction only
  FrictionMethod friction_method = FrictionMethod::kWorkingSet;
  int max_iterations = 500;  // Gauss–Seidel sweeps
  double tolerance = 1e-12;  // on the complementarity residual, relative (see below)
  double equality_compliance = 1e-4;  // kEquality only: ε above, finite, ≥ 0
};

struct ContactSolveReport {
  int iterations = 0;  // Gauss–Seidel sweeps (0 for the direct equality solve)
  // max_i |min(λ_i, c_i)|·Δt‖W‖-scaled, or ‖Δt(W + ε diag W)λ − rhs‖/‖rhs‖ for equality
  double residual = 0.0;
  bool converged = false;
  int newton_steps = 0;  // kFriction, FrictionMethod::kWorkingSet: Newton steps tried (kept or not)
};

// The equality law's compliance on W (above): W_ii ← (1 + ε) W_ii, ε = equality_compliance. The
// frame's solve and the linear contact model built for the haptic step both hold the law so.
void AddEqualityCompliance(double equality_compliance, Eigen::MatrixXd* W);

// Solves for the impulses λ (rows). On entry *lambda is a start (resized and zeroed if its size
// is wrong): Gauss–Seidel's initial guess for kFriction; for kUnilateral the rows with λ > 0
// start in the active set at those λ (negative entries are taken as 0); kEquality ignores it.
// The unilateral solve ends at the LCP's solution from any start (unique where W's symmetric part
// is definite; with nearly redundant contacts, held apart only by its 1e-10 shift, the share of λ
// between them may differ, the force they sum to not). A frame's λ may so depend on the frames
// before it, through the start, within those bounds; friction may have several solutions.
// rows_per_contact must be 3 for kFriction. friction_per_contact, if given (kFriction; one μ ≥ 0
// per contact), replaces options.friction_coefficient contact by contact (a rigid object's own μ).
// bilateral_rows, if given (one entry per row, non-zero: bilateral), marks equality rows among
// unilateral ones (a grasp's, contact/tissue_grasp.h): c_i = 0 with λ_i of either sign, the
// mixed LCP. kEquality holds every row so anyway; kFriction refuses them (std::invalid_argument).
ContactSolveReport SolveContactImpulses(const Eigen::MatrixXd& W, const Eigen::VectorXd& rhs,
                                        double dt_s, int rows_per_contact,
                                        const ContactSolveOptions& options, Eigen::VectorXd* lambda,
                                        const Eigen::VectorXd* friction_per_contact = nullptr,
                                        const std::vector<std::uint8_t>* bilateral_rows = nullptr);

// Fills the given columns of the W a solve reads (see SolveUnilateralByColumns).
using ColumnFiller = std::function<void(const std::vector<Eigen::Index>& columns)>;

// The unilateral law (kUnilateral, as SolveContactImpulses solves it, the same steps) with W read
// only by the columns of the rows that carry or take load, and its diagonal: before the solve reads
// a column it asks `fill_columns` (null: W is whole) for it. A frame whose rows are mostly idle
// (block_press: ~70 loaded of ~210) so forms a third of W. Columns asked for: the rows starting
// with λ > 0 or bilateral, at once; then each entering row. Whatever the solve returns with
// λ ≠ 0 has its column filled. W_diagonal holds W(i, i) of every row.
ContactSolveReport SolveUnilateralByColumns(
    const Eigen::MatrixXd& W, const Eigen::VectorXd& W_diagonal, const ColumnFiller& fill_columns,
    const Eigen::VectorXd& rhs, double dt_s, const ContactSolveOptions& options,
    Eigen::VectorXd* lambda, const std::vector<std::uint8_t>* bilateral_rows = nullptr);

// The pieces of the friction law both friction solvers (the frame's, above, and the haptic
// step's HapticFrictionSolver) share, so that they have one fixed point:
//  - the projection of a tangential impulse onto the disc |λ_t| ≤ radius;
//  - one Gauss–Seidel step of a contact's tangential impulse: λ_t ← Proj(λ_t − c_t/(Δt ω)) onto
//    the disc of radius μλ_n, ω = max(W_11, W_22) + |W_12| over the contact's 2 × 2 tangential
//    block of W (its symmetric part; Gershgorin: ω ≥ the block's largest eigenvalue, so the step
//    never overshoots). Zero when the disc is (μλ_n = 0) or ω is not positive (nothing can change
//    the contact's tangential velocity: it carries no friction); never divides by zero;
//  - the fixed-point residual of a friction solution: per contact |min(λ_n, c_n/(ΔtW_nn))| and
//    |λ_t − Proj(λ_t − c_t/(Δt ω))|, c = ΔtWλ − rhs, relative to max |λ| (absolute at λ = 0).
//    Zero exactly when Coulomb's law holds: λ_n ≥ 0 ⟂ c_n ≥ 0, |λ_t| ≤ μλ_n, c_t = 0 inside the
//    disc and λ_t opposite c_t on its rim.
Eigen::Vector2d ProjectOntoDisc(const Eigen::Vector2d& lambda_t, double radius);
Eigen::Vector2d StepTangentialImpulse(const Eigen::Vector2d& lambda_t, const Eigen::Vector2d& c_t,
                                      const Eigen::Matrix2d& W_tt, double dt_s, double radius);
double CalcFrictionResidual(const Eigen::MatrixXd& W, const Eigen::VectorXd& rhs, double dt_s,
                            double mu, const Eigen::VectorXd* mu_per_contact,
                            const Eigen::VectorXd& lambda);

}  // namespace hapsim::contact
