#include "contact/haptic_lcp_solver.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace hapsim::contact {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;
using MatrixX6d = Eigen::Matrix<double, Eigen::Dynamic, 6>;

// Border capacity: rows that entered or left the active set since the base was factorised.
// Past it the base is refactorised. 32 keeps the border system (≤ 38 × 38, fixed capacity, on
// the stack) cheap next to the O(n²) complementarity check.
constexpr int kMaxItems = 32;
constexpr int kMaxBorder = 6 + kMaxItems;
using BorderMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kMaxBorder, kMaxBorder>;
using BorderVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxBorder, 1>;

// A row enters when c_i < −kEnteringTolerance · max(1, ‖rhs‖∞), as in SolveContactImpulses.
constexpr double kEnteringTolerance = 1e-12;
// A converged solve whose complementarity residual (CalcResidual) exceeds this is redone from a
// fresh factorisation. Exact solves reach ~1e-14; the tests ask for 1e-10.
constexpr double kRetryResidual = 1e-9;
// A converged solve whose residual still exceeds this after the retry is a failure (the caller
// renders the linear model): rows refused as dependent (RunActiveSet) leave a residual of the
// conditioning's order, 7e-6 to 7e-4 in a trainer session's nearly dependent rows; far more would
// be a contact that presses without pushing.
constexpr double kAcceptResidual = 1e-2;

// S̄: the symmetric part of a 3×3 compliance block if positive definite, else a multiple of the
// identity of the same size (any symmetric positive definite choice is exact; close to S keeps
// ΔS small).
Eigen::Matrix3d CalcSymmetricPositive(const Eigen::Matrix3d& S) {
  const Eigen::Matrix3d symmetric = 0.5 * (S + S.transpose());
  const Eigen::LLT<Eigen::Matrix3d> llt(symmetric);
  if (llt.info() == Eigen::Success) return symmetric;
  return (S.norm() / std::sqrt(3.0)) * Eigen::Matrix3d::Identity();
}

// K = L Lᵀ in place: L overwrites K's lower triangle (the upper one is not read). Left-looking,
// column j at a time (Golub & Van Loan, Algorithm 4.2.1):
//   K(j:n, j) −= L(j:n, 0:j) L(j, 0:j)ᵀ,  L(j, j) = √K(j, j),
//   L(j+1:n, j) = K(j+1:n, j) / L(j, j).
// Only matrix–vector products, whose temporaries Eigen keeps on the stack: Eigen's LLT is
// blocked, and its matrix–matrix updates take heap workspace from ~400 rows on (cache-size
// dependent), which the 1 kHz step must never do. Speed within 0.8–1.35× of Eigen's LLT from 32
// to 512 rows (faster below ~100). Returns false, K part-overwritten, if K is not positive
// definite to working precision: a pivot at most kDependentPivot × its row's diagonal. Row j is
// then dependent on rows 0..j−1 to within 1e-10 (pivot ÷ diagonal is sin² of the angle between
// row j and the span of the rows before it, in K's metric), a condition number past 1e10 whose
// impulses are noise. An exact test (pivot > 0) left the verdict to rounding: a twin row passed
// it under clang -O1 and was held with impulses of −4.9 N and +4.9 N + λ that cancel (the ASan
// build's haptic_hybrid_test), and failed it under GCC -O2. A pivot's rounding grows with j (about
// j ulps of the diagonal): 1e-10 stays ~10³ above it at 512 rows. Only the base factorisation
// (Rebase) applies this test; a row entering through the border is checked by the border's LU,
// and a near-twin admitted there is refused at the next rebase.
bool FactorCholeskyInPlace(Eigen::Ref<Eigen::MatrixXd> K) {
  constexpr double kDependentPivot = 1e-10;
  const Eigen::Index n = K.rows();
  for (Eigen::Index j = 0; j < n; ++j) {
    const double diagonal = K(j, j);
    if (j > 0)
      K.col(j).tail(n - j).noalias() -= K.bottomLeftCorner(n - j, j) * K.row(j).head(j).transpose();
    const double pivot = K(j, j);
    if (!(pivot > kDependentPivot * diagonal)) return false;  // also NaN
    const double L_jj = std::sqrt(pivot);
    K(j, j) = L_jj;
    K.col(j).tail(n - j - 1) /= L_jj;
  }
  return true;
}

}  // namespace

// All scratch, sized once for max_rows. Notation: n rows; x = Δt λ, so the LCP reads
// w = W x − r ≥ 0, x ≥ 0, xᵀw = 0 with r = rhs; A the active set; B the base rows (ascending),
// k0 = |B|, K0 = W̄_BB = L Lᵀ. The border lists "items": rows that entered A from outside B
// (column V_t = W̄_Bj) and rows of B that left A (column V_t = e_i). With W(t) = W̄ + U ΔS Uᵀ and
// y = ΔS Uᵀx, the equality W(t)_AA x_A = r_A is the bordered system
//
//   K0 x_B + U_B y + Σ_t V_t ξ_t = r_B               (base rows; a left row's equation is
//                                                     absorbed by its multiplier ξ_t)
//   ΔS (U_Bᵀ x_B + Σ_entered U_jᵀ ξ_t) − y = 0
//   W̄_jB x_B + U_j y + Σ_entered W̄_jj' ξ_t' = r_j   (entered row j, ξ_t = x_j)
//   e_iᵀ x_B = 0                                     (left row i)
//
// whose Schur complement on K0 is m × m, m = 6 + items. Y = L⁻¹[U_B V] and P = YᵀY = [U_B V]ᵀK0⁻¹
// [U_B V] do not depend on the step and are updated one column (one forward substitution) per
// change; h = L⁻¹ target_B and q = Yᵀh depend on the step's targets (body_rhs unless Solve is
// given others) and are redone when they change (RefreshTargets). With r_B = target_B − U_B s_free
// everything else step-dependent in the border is 6-dimensional, and x_B = L⁻ᵀ(h − Y [s_free + y;
// ξ]) costs one back substitution per solve.
// The rows themselves (n, W, U, body_rhs) are the ContactRowCache it extends.
struct HapticLcpSolver::Workspace : ContactRowCache {
  explicit Workspace(int max_rows_in)
      : ContactRowCache(max_rows_in),
        max_rows(max_rows_in),
        U_bar(max_rows_in, 6),
        base_rows(max_rows_in, -1),
        base_pos(max_rows_in, -1),
        item_of_row(max_rows_in, -1),
        L(max_rows_in, max_rows_in),
        U_B(max_rows_in, 6),
        U_bar_B(max_rows_in, 6),
        h(max_rows_in),
        Y(max_rows_in, kMaxBorder),
        P(kMaxBorder, kMaxBorder),
        q(kMaxBorder),
        active(max_rows_in, 0),
        held(max_rows_in, 0),
        refused(max_rows_in, 0),
        active_before_rebase(max_rows_in, 0),
        frame_impulse_N(max_rows_in),
        r(max_rows_in),
        x(max_rows_in),
        z(max_rows_in),
        w(max_rows_in),
        column(max_rows_in),
        target(max_rows_in),
        C(kMaxBorder, kMaxBorder),
        rho(kMaxBorder),
        xi(kMaxBorder),
        coef(kMaxBorder),
        C_lu(kMaxBorder) {
    W.setZero();
    L.setZero();
    Y.setZero();
    P.setZero();
    x.setZero();
  }

  // W̄_ij = W_body,ij (lower triangle) + U_i S̄ U_jᵀ.
  double W_lower(int i, int j) const { return i >= j ? BodyLower(i, j) : BodyLower(j, i); }
  double W_bar(int i, int j) const { return W_lower(i, j) + U_bar.row(i).dot(U.row(j)); }

  bool Rebase();
  void GuessActiveSet(const ContactRows& rows, const Eigen::VectorXd& push, bool hold);
  bool StartFromGuess();
  bool ReleaseRowsPullingPastTheirPush(double dt_s);
  void RefreshTargets();
  // The frame's impulses as the cached rows gave them: the held set and each held row's release
  // threshold (ReleaseRowsPullingPastTheirPush) come from them.
  bool HoldsFrameSet(const ContactRows& rows) const {
    const bool frame_set = rows.lambda_frame_N.size() == n;
    for (int i = 0; i < n; ++i)
      if (frame_impulse_N[i] != (frame_set ? rows.lambda_frame_N[i] : 0.0)) return false;
    return true;
  }
  void ForwardSolveInPlace(int first, Eigen::Ref<Eigen::VectorXd> v) const;
  void BackSolveInPlace(Eigen::Ref<Eigen::VectorXd> v) const;
  void AddEnteredRow(int j);
  void AddLeftRow(int i);
  void RemoveItem(int t);
  void Activate(int i);
  void Deactivate(int i);
  bool SolveOnActiveSet();
  void CalcSlack();
  enum class End { kConverged, kFailed, kOutOfBudget };
  End RunActiveSet(double tolerance, int max_solves, int* iterations);
  bool ShrinkToFeasible(int* iterations);
  bool EnterRow(int entering, int* iterations);
  double CalcResidual(double dt_s) const;
  // Whether refactorising is cheaper than bordering `num_leaving` rows leaving the base at
  // once. Rough flop model: a border item costs a forward substitution and a row of P, ~2 k0²;
  // a refactorisation of the k = k0 − num_leaving remaining rows k³/3 at about twice the speed
  // (blocked) plus ~10 k² for the assembly and the seven substitutions. Past half the border
  // capacity the border would soon overflow anyway.
  bool RebaseIsCheaper(int num_leaving) const {
    const double k = k0 - num_leaving;
    return num_leaving > kMaxItems / 2 ||
           2.0 * num_leaving * k0 * k0 > k * k * k / 6.0 + 10.0 * k * k;
  }

  const int max_rows;
  // This step's tool: S = blockdiag(A_v⁻¹, M⁻¹A_L⁻¹), s_free = (v_free, ω_free).
  Matrix6d S = Matrix6d::Zero();
  Vector6d s_free = Vector6d::Zero();
  // The base.
  Matrix6d S_bar = Matrix6d::Zero();
  MatrixX6d U_bar;  // (max x 6) U S̄
  int k0 = 0;
  std::vector<int> base_rows;    // (max) the k0 base rows, ascending
  std::vector<int> base_pos;     // (max) position in the base, −1 outside
  std::vector<int> item_of_row;  // (max) border item of a row, −1 none
  Eigen::MatrixXd L;             // (max x max) lower triangle: Cholesky factor of K0
  MatrixX6d U_B, U_bar_B;        // (max x 6) U and U S̄ gathered at the base rows
  Eigen::VectorXd h;             // (max) L⁻¹ body_rhs_B
  Eigen::MatrixXd Y;             // (max x kMaxBorder) L⁻¹ [U_B V]
  BorderMatrix P;                // YᵀY = [U_B V]ᵀ K0⁻¹ [U_B V]
  BorderVector q;                // Yᵀh
  int num_items = 0;
  std::array<int, kMaxItems> item_row{};
  std::array<bool, kMaxItems> item_entered{};
  bool rebase_pending = true;
  int num_factorizations = 0;
  // Active set and iterates (rows).
  std::vector<std::uint8_t> active;  // (max)
  // (max) rows held as equalities (HapticLcpSolver's hold_frame_contacts: the frame's active
  // rows): always in the active set, their λ of either sign, never a complementarity test.
  std::vector<std::uint8_t> held;
  int num_held = 0;
  // (max) rows refused entry since x last moved (RunActiveSet: z ≤ 0 on entering, or a fresh
  // factorisation refusing them, round-off), and the active set kept across such a refactorisation.
  std::vector<std::uint8_t> refused;
  std::vector<std::uint8_t> active_before_rebase;
  // (max) λ_frame per row as the rows last gave it (0 without the frame's impulses; > 0: the
  // frame's active rows): unstamped rows are the cached ones only if these match too, for they
  // choose the held set and its release thresholds.
  Eigen::VectorXd frame_impulse_N;
  Eigen::VectorXd r, x, z, w, column;
  Eigen::VectorXd target;  // (max) this step's body_rhs (rows.body_rhs, or Solve's targets)
  // Border system of one solve.
  BorderMatrix C;
  BorderVector rho, xi, coef;
  Eigen::PartialPivLU<BorderMatrix> C_lu;
};

// v ← L⁻¹ v for a v that is zero above row `first` (only rows first.. are touched).
void HapticLcpSolver::Workspace::ForwardSolveInPlace(int first,
                                                     Eigen::Ref<Eigen::VectorXd> v) const {
  if (first >= k0) return;
  L.block(first, first, k0 - first, k0 - first)
      .triangularView<Eigen::Lower>()
      .solveInPlace(v.segment(first, k0 - first));
}

// v ← L⁻ᵀ v.
void HapticLcpSolver::Workspace::BackSolveInPlace(Eigen::Ref<Eigen::VectorXd> v) const {
  if (k0 == 0) return;
  L.topLeftCorner(k0, k0).triangularView<Eigen::Lower>().adjoint().solveInPlace(v);
}

// Makes the current active set the base: K0 = W̄_AA, S̄ from this step's S, border cleared.
// Returns false (and leaves an empty base, with every row inactive) if K0 is not positive
// definite, i.e. the active rows are dependent: W(t)_AA is then singular too, whatever S.
bool HapticLcpSolver::Workspace::Rebase() {
  rebase_pending = false;
  for (int t = 0; t < num_items; ++t) item_of_row[item_row[t]] = -1;
  num_items = 0;
  S_bar.setZero();
  S_bar.topLeftCorner<3, 3>() = CalcSymmetricPositive(S.topLeftCorner<3, 3>());
  S_bar.bottomRightCorner<3, 3>() = CalcSymmetricPositive(S.bottomRightCorner<3, 3>());
  U_bar.topRows(n).noalias() = U.topRows(n) * S_bar;
  k0 = 0;
  for (int i = 0; i < n; ++i) {
    base_pos[i] = -1;
    if (active[i]) {
      base_rows[k0] = i;
      base_pos[i] = k0++;
    }
  }
  for (int a = 0; a < k0; ++a) {
    U_B.row(a) = U.row(base_rows[a]);
    U_bar_B.row(a) = U_bar.row(base_rows[a]);
    h[a] = target[base_rows[a]];
  }
  if (k0 > 0) {
    auto K = L.topLeftCorner(k0, k0);
    for (int b = 0; b < k0; ++b)
      for (int a = b; a < k0; ++a) K(a, b) = BodyLower(base_rows[a], base_rows[b]);  // ascending
    K.triangularView<Eigen::Lower>() += U_bar_B.topRows(k0) * U_B.topRows(k0).transpose();
    ++num_factorizations;
    if (!FactorCholeskyInPlace(K)) {
      for (int a = 0; a < k0; ++a) {
        active[base_rows[a]] = 0;
        base_pos[base_rows[a]] = -1;
      }
      k0 = 0;
      P.topLeftCorner<6, 6>().setZero();
      q.head<6>().setZero();
      return false;
    }
  }
  for (int c = 0; c < 6; ++c) {
    Y.col(c).head(k0) = U_B.col(c).head(k0);
    ForwardSolveInPlace(0, Y.col(c).head(k0));
  }
  ForwardSolveInPlace(0, h.head(k0));
  P.topLeftCorner<6, 6>().noalias() = Y.topLeftCorner(k0, 6).transpose() * Y.topLeftCorner(k0, 6);
  q.head<6>().noalias() = Y.topLeftCorner(k0, 6).transpose() * h.head(k0);
  return true;
}

// New contacts (their indices say nothing about the old active set): guess the frame's active
// set, or else the rows that ask for a push, push_i > 0 (r_i = b_i − c_free,i). With `hold`, the
// frame's active rows are held as equalities from now on (the linear contact model's rows).
void HapticLcpSolver::Workspace::GuessActiveSet(const ContactRows& rows,
                                                const Eigen::VectorXd& push, bool hold) {
  const bool frame_set = rows.lambda_frame_N.size() == n;
  num_held = 0;
  for (int i = 0; i < n; ++i) {
    frame_impulse_N[i] = frame_set ? rows.lambda_frame_N[i] : 0.0;
    const bool grasp_row = i < bilateral;
    held[i] = grasp_row || (hold && frame_impulse_N[i] > 0.0);
    num_held += held[i];
    active[i] = grasp_row || (frame_set ? rows.lambda_frame_N[i] > 0.0 : push[i] > 0.0);
  }
  rebase_pending = true;
}

// Factorises the guessed set. A dependent guess leaves an empty base (Rebase): a cold start. With
// held rows the guess is the held set itself, and dependent held rows (redundant contacts, which
// the frame's solve admits through its small diagonal shift, contact_solver.cc) have no unique
// equality solution to hold: these rows are then all solved unilaterally, as the lcp mode solves
// them, until new rows come (which keeps the tool from passing through, unlike a fall-back to the
// linear model, and costs no retry at the next steps).
//
// A grasp's rows (bilateral) are then tried on their own: they hold the tissue, while the frame's
// held contacts are the ones that may be redundant. Returns false if even they are dependent:
// they cannot be solved unilaterally (the tissue would stop pulling), so the solve fails and the
// step falls back to the linear contact model, which holds them by a rank-revealing solve.
bool HapticLcpSolver::Workspace::StartFromGuess() {
  if (Rebase() || num_held == 0) return true;
  std::fill(held.begin(), held.begin() + n, std::uint8_t{0});
  num_held = 0;
  if (bilateral == 0) return true;
  for (int i = 0; i < bilateral; ++i) held[i] = active[i] = 1;
  num_held = bilateral;
  return Rebase();
}

// A held row may pull (λ < 0), as the linear contact model's rows do, by a little: the model's
// correction of the frame's push as the tool moves on (on block_press at most 2 % of the frame's
// total push). One that pulls harder than it pushed at the frame (x_i < −Δt λ_frame,i) is held
// against a twin: a free row nearly dependent on it (several tool points on one body face share
// its three nodes and its normal; two_organs' rows came in such threes) that has engaged at its
// own, tracked gap while the held row keeps closing the frame's gap. The equality and the
// inequality then disagree along a direction W hardly resists, and the solve meets them with
// opposite impulses that grow without bound (seen: ±1e10 N, and 26–260 N reaching the tool on
// two_organs with the exact compliance; pulls past the push in 1,678 of polyp's 3,890 steps,
// cancelling to within its 0.4 N). Such rows are released, solved unilaterally from then on as
// the lcp mode solves them, until new rows come; true if any.
bool HapticLcpSolver::Workspace::ReleaseRowsPullingPastTheirPush(double dt_s) {
  bool released = false;
  for (int i = 0; i < n; ++i) {
    if (!held[i] || i < bilateral || !(x[i] < -dt_s * frame_impulse_N[i])) continue;
    held[i] = 0;
    --num_held;
    released = true;
  }
  return released;
}

// New targets on the same rows and base (the hybrid mode's free rows move every step): h = L⁻¹
// target_B and q = Yᵀh, one forward substitution and one product, O(k0² + k0 m); P and the
// factor do not depend on the targets. (A left row's column of Y is zero above its base
// position, so the whole dot product is the one AddLeftRow formed.)
void HapticLcpSolver::Workspace::RefreshTargets() {
  for (int a = 0; a < k0; ++a) h[a] = target[base_rows[a]];
  ForwardSolveInPlace(0, h.head(k0));
  const int m = 6 + num_items;
  q.head(m).noalias() = Y.topLeftCorner(k0, m).transpose() * h.head(k0);
}

// Border item for row j ∉ B entering A: column V = W̄_Bj.
void HapticLcpSolver::Workspace::AddEnteredRow(int j) {
  const int c = 6 + num_items;
  auto V = column.head(k0);
  for (int a = 0; a < k0; ++a) V[a] = W_lower(base_rows[a], j);
  V.noalias() += U_bar_B.topRows(k0) * U.row(j).transpose();
  auto y = Y.col(c).head(k0);
  y = V;
  ForwardSolveInPlace(0, y);
  for (int b = 0; b <= c; ++b) P(c, b) = P(b, c) = y.dot(Y.col(b).head(k0));
  q[c] = y.dot(h.head(k0));
  item_row[num_items] = j;
  item_entered[num_items] = true;
  item_of_row[j] = num_items++;
}

// Border item for base row i leaving A: column V = e_i.
void HapticLcpSolver::Workspace::AddLeftRow(int i) {
  const int c = 6 + num_items;
  const int p = base_pos[i];
  auto y = Y.col(c).head(k0);  // L⁻¹ e_p is zero above p
  y.setZero();
  y[p] = 1.0;
  ForwardSolveInPlace(p, y);
  const int tail = k0 - p;
  for (int b = 0; b <= c; ++b) P(c, b) = P(b, c) = y.tail(tail).dot(Y.col(b).segment(p, tail));
  q[c] = y.tail(tail).dot(h.segment(p, tail));
  item_row[num_items] = i;
  item_entered[num_items] = false;
  item_of_row[i] = num_items++;
}

// Drops item t; the last item takes its place.
void HapticLcpSolver::Workspace::RemoveItem(int t) {
  const int last = num_items - 1;
  const int m = 6 + num_items;
  item_of_row[item_row[t]] = -1;
  if (t != last) {
    const int ct = 6 + t, cl = 6 + last;
    Y.col(ct).head(k0) = Y.col(cl).head(k0);
    P.col(ct).head(m) = P.col(cl).head(m);
    P.row(ct).head(m) = P.row(cl).head(m);
    q[ct] = q[cl];
    item_row[t] = item_row[last];
    item_entered[t] = item_entered[last];
    item_of_row[item_row[t]] = t;
  }
  num_items = last;
}

void HapticLcpSolver::Workspace::Activate(int i) {
  active[i] = 1;
  if (rebase_pending) return;
  if (base_pos[i] >= 0) {
    RemoveItem(item_of_row[i]);  // a base row that had left comes back
  } else if (num_items < kMaxItems) {
    AddEnteredRow(i);
  } else {
    rebase_pending = true;
  }
}

void HapticLcpSolver::Workspace::Deactivate(int i) {
  active[i] = 0;
  if (rebase_pending) return;
  if (base_pos[i] < 0) {
    RemoveItem(item_of_row[i]);  // an entered row leaves again
  } else if (num_items < kMaxItems) {
    AddLeftRow(i);
  } else {
    rebase_pending = true;
  }
}

// z_A solving W(t)_AA z_A = r_A, z = 0 off A, through the Schur complement of the border.
bool HapticLcpSolver::Workspace::SolveOnActiveSet() {
  if (rebase_pending && !Rebase()) return false;
  const int m = 6 + num_items;
  const Matrix6d dS = S - S_bar;
  const auto Pm = P.topLeftCorner(m, m);
  C.resize(m, m);
  rho.resize(m);
  C.topLeftCorner<6, 6>().noalias() = -dS * Pm.topLeftCorner<6, 6>();
  C.topLeftCorner<6, 6>().diagonal().array() -= 1.0;
  rho.head<6>().noalias() = -dS * (q.head<6>() - Pm.topLeftCorner<6, 6>() * s_free);
  for (int t = 0; t < num_items; ++t) {
    const int c = 6 + t;
    const int j = item_row[t];
    const bool entered = item_entered[t];
    const Vector6d u_j = entered ? Vector6d(U.row(j).transpose()) : Vector6d::Zero();
    C.block<6, 1>(0, c).noalias() = dS * (u_j - Pm.block<6, 1>(0, c));
    C.block<1, 6>(c, 0) = u_j.transpose() - Pm.block<1, 6>(c, 0);
    for (int s = 0; s < num_items; ++s) {
      const bool both_entered = entered && item_entered[s];
      C(c, 6 + s) = (both_entered ? W_bar(j, item_row[s]) : 0.0) - Pm(c, 6 + s);
    }
    rho[c] = (entered ? r[j] : 0.0) - (q[c] - Pm.block<1, 6>(c, 0).dot(s_free));
  }
  C_lu.compute(C);
  xi.resize(m);
  xi = C_lu.solve(rho);
  // x_B = K0⁻¹(r_B − U_B y − V ξ) = L⁻ᵀ(h − Y [s_free + y; ξ]).
  coef = xi;
  coef.head<6>() += s_free;
  auto x_B = column.head(k0);
  x_B = h.head(k0);
  x_B.noalias() -= Y.topLeftCorner(k0, m) * coef;
  BackSolveInPlace(x_B);
  z.head(n).setZero();
  for (int a = 0; a < k0; ++a) z[base_rows[a]] = x_B[a];
  for (int t = 0; t < num_items; ++t) z[item_row[t]] = item_entered[t] ? xi[6 + t] : 0.0;
  return z.head(n).allFinite();
}

// w = W(t) x − r over all rows.
void HapticLcpSolver::Workspace::CalcSlack() {
  // W_body x: the coupled rows' block (lower triangle), then each uncoupled row's own entry.
  w.head(coupled).noalias() =
      W.topLeftCorner(coupled, coupled).selfadjointView<Eigen::Lower>() * x.head(coupled);
  w.segment(coupled, n - coupled) =
      W.diagonal().segment(coupled, n - coupled).cwiseProduct(x.segment(coupled, n - coupled));
  const Vector6d Ux = U.topRows(n).transpose() * x.head(n);
  const Vector6d SUx = S * Ux;
  w.head(n).noalias() += U.topRows(n) * SUx;
  w.head(n) -= r.head(n);
}

// Shrinks the guessed set until its equality solution is positive: a feasible start for the
// active-set iteration, optimal on its face. Many rows leaving at once (a poor guess for new rows)
// are cheaper to refactorise than to border. False if an equality solve failed.
bool HapticLcpSolver::Workspace::ShrinkToFeasible(int* iterations) {
  while (true) {
    ++*iterations;
    if (!SolveOnActiveSet()) return false;
    int num_leaving = 0;
    for (int i = 0; i < n; ++i) num_leaving += active[i] && !held[i] && !(z[i] > 0.0);
    if (num_leaving == 0) break;
    if (RebaseIsCheaper(num_leaving)) rebase_pending = true;
    for (int i = 0; i < n; ++i)
      if (active[i] && !held[i] && !(z[i] > 0.0)) Deactivate(i);
  }
  x.head(n) = z.head(n);
  return true;
}

// One Lawson–Hanson entry: row `entering` joins the set; solve on it; step back along the segment
// (ratio test) when an active x would turn negative and drop the rows that reached zero, until the
// step is whole. A row that cannot enter (RunActiveSet) is refused instead. False if an equality
// solve failed otherwise.
bool HapticLcpSolver::Workspace::EnterRow(int entering, int* iterations) {
  Activate(entering);
  // A full border puts the entering row into a fresh factorisation (Rebase), which clears the set
  // if it fails: keep the set to put back.
  const bool rebase_with_entering = rebase_pending;
  if (rebase_with_entering) std::copy_n(active.begin(), n, active_before_rebase.begin());
  for (bool entered = true;; entered = false) {
    ++*iterations;
    if (!SolveOnActiveSet()) {
      if (!(entered && rebase_with_entering)) return false;
      std::copy_n(active_before_rebase.begin(), n, active.begin());
      active[entering] = 0;
      refused[entering] = 1;
      rebase_pending = true;
      return true;
    }
    if (entered && !(z[entering] > 0.0)) {
      Deactivate(entering);
      refused[entering] = 1;
      return true;
    }
    // Ratio test: the longest step along z − x keeping x ≥ 0. The row that blocks it is set to
    // zero explicitly (x + step (z − x) may round to a tiny positive value, and a row left in the
    // set that way would stall the iteration with ever smaller steps).
    double step = 1.0;
    int blocking = -1;
    for (int i = 0; i < n; ++i) {
      if (!active[i] || held[i] || z[i] > 0.0) continue;
      const double decrease = x[i] - z[i];
      const double ratio = decrease > 0.0 ? x[i] / decrease : 0.0;
      if (ratio < step) step = ratio, blocking = i;
    }
    for (int i = 0; i < n; ++i)
      if (active[i]) x[i] += step * (z[i] - x[i]);
    if (step > 0.0)
      for (int i = 0; i < n; ++i) refused[i] = 0;
    if (blocking < 0) return true;
    x[blocking] = 0.0;
    bool any_active = num_held > 0;  // held rows stay: solve on them again
    for (int i = 0; i < n; ++i) {
      if (!active[i] || held[i]) continue;
      if (x[i] > 0.0) {
        any_active = true;
      } else {
        x[i] = 0.0;
        Deactivate(i);
      }
    }
    if (!any_active) return true;
  }
}

// The active-set iteration from the current active set, to complementarity within
// `tolerance` (on w). Leaves x and w at the solution. Fails if an equality solve failed (singular
// W on the active set) or 3n + 10 rows entered without convergence. With max_solves > 0, stops
// once `*iterations` has reached it, at the top of an outer iteration: x is then feasible (≥ 0
// off the held rows), optimal on its active set, and the set is kept for the next call.
HapticLcpSolver::Workspace::End HapticLcpSolver::Workspace::RunActiveSet(double tolerance,
                                                                         int max_solves,
                                                                         int* iterations) {
  if (!ShrinkToFeasible(iterations)) return End::kFailed;
  // Lawson–Hanson: the most violated row enters (EnterRow), until none is violated.
  //
  // A row whose own z comes out ≤ 0 on entering cannot enter: in exact arithmetic the most
  // violated row always gets z > 0 (W positive definite on the set), so this is round-off among
  // nearly dependent rows (a probe on a few hundred of a fine surface's contacts). Entered, it
  // would leave at once by the ratio test with x unchanged, and be the most violated again: the
  // iteration would cycle to its entering limit (seen: 1,544 solves, 17 ms, in one 1 kHz step of
  // a trainer session). Lawson & Hanson's NNLS refuses such a row (their step 6: set its w to 0
  // and choose again); so does this, until x next moves. The same holds for a row whose entry
  // overflows the border and whose fresh factorisation then finds it dependent on the set to
  // working precision (FactorCholeskyInPlace's pivot test): it is refused, and the set is
  // factorised again without it. What is left violated only by refused rows is round-off, which
  // Solve's residual tests judge (a retry from a fresh factor, then kAcceptResidual).
  for (int i = 0; i < n; ++i) refused[i] = 0;
  for (int outer = 0;; ++outer) {
    CalcSlack();
    int entering = -1;
    double most_violated = -tolerance;
    for (int i = 0; i < n; ++i)
      if (!active[i] && !refused[i] && w[i] < most_violated) most_violated = w[i], entering = i;
    if (entering < 0) return End::kConverged;
    if (outer == 3 * n + 10) return End::kFailed;
    if (max_solves > 0 && *iterations >= max_solves) return End::kOutOfBudget;
    if (!EnterRow(entering, iterations)) return End::kFailed;
  }
}

// ContactSolveReport's measure, max_i |min(λ_i, c_i/(Δt W_ii))| / max λ, from x = Δt λ and
// c = w (after RunActiveSet). A row with λ_i = 0 and c_i ≥ 0 adds nothing (W_ii > 0): most of
// the frame's far candidates, whose W_ii is then not formed.
double HapticLcpSolver::Workspace::CalcResidual(double dt_s) const {
  double residual = 0.0;
  for (int i = 0; i < n; ++i) {
    if (x[i] == 0.0 && w[i] >= 0.0 && !held[i]) continue;
    const double W_ii = W(i, i) + U.row(i).dot(S * U.row(i).transpose());
    const double slack = w[i] / (dt_s * W_ii);  // a held row's only condition: c_i = 0
    residual = std::max(residual, std::abs(held[i] ? slack : std::min(x[i] / dt_s, slack)));
  }
  const double scale = x.head(n).lpNorm<Eigen::Infinity>() / dt_s;
  return scale > 0.0 ? residual / scale : residual;
}

// One retry from a fresh factorisation should round-off in the border (or rows refused as
// dependent) have spoilt the complementarity. A step out of its budget keeps its feasible iterate
// and is not retried: the next step goes on from its active set; nor is one that has spent its
// budget converging.
bool HapticLcpSolver::RunActiveSetWithRetry(double dt_s, double tolerance) {
  Workspace& ws = *ws_;
  bool converged = false;
  last_out_of_budget_ = false;
  for (int attempt = 0; attempt < 2; ++attempt) {
    if (attempt == 1) ws.rebase_pending = true;
    const Workspace::End end = ws.RunActiveSet(tolerance, max_solves_per_step_, &last_iterations_);
    converged = end != Workspace::End::kFailed;
    last_out_of_budget_ = end == Workspace::End::kOutOfBudget;
    if (!converged) break;
    last_residual_ = ws.CalcResidual(dt_s);
    const bool budget_spent = max_solves_per_step_ > 0 && last_iterations_ >= max_solves_per_step_;
    if (last_out_of_budget_ || budget_spent || !(last_residual_ > kRetryResidual)) break;
  }
  return converged;
}

HapticLcpSolver::HapticLcpSolver(int max_rows, int friction_sweeps, bool hold_frame_contacts,
                                 int max_solves_per_step)
    : hold_frame_contacts_(hold_frame_contacts), max_solves_per_step_(max_solves_per_step) {
  if (max_rows < 0) throw std::invalid_argument("HapticLcpSolver: max_rows must be ≥ 0");
  if (max_solves_per_step < 0)
    throw std::invalid_argument("HapticLcpSolver: max_solves_per_step must be ≥ 0");
  if (friction_sweeps < 0)
    throw std::invalid_argument("HapticLcpSolver: friction_sweeps must be ≥ 0");
  ws_ = std::make_unique<Workspace>(max_rows);
  if (friction_sweeps > 0)
    friction_ = std::make_unique<HapticFrictionSolver>(max_rows, friction_sweeps);
}

HapticLcpSolver::~HapticLcpSolver() = default;
HapticLcpSolver::HapticLcpSolver(HapticLcpSolver&&) noexcept = default;
HapticLcpSolver& HapticLcpSolver::operator=(HapticLcpSolver&&) noexcept = default;

int HapticLcpSolver::max_rows() const { return ws_->max_rows; }
int HapticLcpSolver::friction_sweeps() const { return friction_ ? friction_->max_sweeps() : 0; }

Eigen::Ref<const Eigen::VectorXd> HapticLcpSolver::last_impulses() const {
  if (!last_solved_) return ws_->x.head(0);
  if (last_was_friction_) return friction_->last_impulses();
  return ws_->x.head(std::max(ws_->n, 0));
}

bool HapticLcpSolver::Prepare(const ContactRows& rows, const ToolStepSystem& tool) {
  if (rows.rows_per_contact == 3) return friction_ && friction_->Prepare(rows);
  Workspace& ws = *ws_;
  const int n = rows.num_rows();
  if (n == 0 || n > ws.max_rows || rows.rows_per_contact != 1 || !HasConsistentShape(rows) ||
      !(tool.dt_s > 0.0))
    return false;
  if (!CalcToolCompliance(tool, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), &ws.S,
                          &ws.s_free) ||
      !ws.Take(rows)) {
    ws.n = -1;
    return false;
  }
  ws.target.head(n) = rows.body_rhs;
  ws.GuessActiveSet(rows, rows.body_rhs, hold_frame_contacts_);
  ws.num_factorizations = 0;
  if (!ws.StartFromGuess()) {
    ws.n = -1;
    return false;
  }
  return true;
}

bool HapticLcpSolver::Solve(const ContactRows& rows, const ToolStepSystem& tool,
                            const Eigen::Vector3d& F_hat_N, const Eigen::Vector3d& T_hat_N_m,
                            Eigen::Vector3d* F_c_N, Eigen::Vector3d* T_c_N_m,
                            const Eigen::VectorXd* targets) {
  Workspace& ws = *ws_;
  F_c_N->setZero();
  T_c_N_m->setZero();
  last_iterations_ = 0;
  last_residual_ = 0.0;
  last_num_active_ = 0;
  last_num_factorizations_ = 0;
  last_out_of_budget_ = false;
  ws.num_factorizations = 0;
  last_solved_ = false;
  last_was_friction_ = rows.rows_per_contact == 3 && friction_;
  if (last_was_friction_) {
    last_solved_ = friction_->Solve(rows, tool, F_hat_N, T_hat_N_m, F_c_N, T_c_N_m);
    last_iterations_ = friction_->last_iterations();
    last_residual_ = friction_->last_residual();
    last_num_active_ = friction_->last_num_active();
    return last_solved_;
  }
  const int n = rows.num_rows();
  if (n > ws.max_rows || rows.rows_per_contact != 1 || !HasConsistentShape(rows) ||
      !(tool.dt_s > 0.0))
    return false;
  const double dt_s = tool.dt_s;
  if (!CalcToolCompliance(tool, F_hat_N, T_hat_N_m, &ws.S, &ws.s_free)) return false;

  if (n == 0) {
    ws.n = 0;
    ws.rebase_pending = true;
    last_solved_ = true;
    return true;
  }
  if (targets != nullptr && (targets->size() < n || !targets->head(n).allFinite())) return false;
  bool new_rows = !ws.Holds(rows);
  // Unstamped rows equal in every entry but the frame's impulses would hold another set.
  if (!new_rows && hold_frame_contacts_ && rows.stamp == 0) new_rows = !ws.HoldsFrameSet(rows);
  if (new_rows && !ws.Take(rows)) return false;
  // Without targets the cached body_rhs (rows stamped as cached are, by contract, the cache's).
  const Eigen::VectorXd& source = targets != nullptr ? *targets : ws.body_rhs;
  const auto step_rhs = source.head(n);
  const bool targets_changed = new_rows || ws.target.head(n) != step_rhs;
  ws.target.head(n) = step_rhs;
  ws.r.head(n) = step_rhs;
  ws.r.head(n).noalias() -= ws.U.topRows(n) * ws.s_free;
  if (new_rows) ws.GuessActiveSet(rows, ws.r, hold_frame_contacts_);
  if (ws.rebase_pending) {
    if (!ws.StartFromGuess()) {
      ws.n = -1;  // the grasp's rows cannot be held: fail (HapticStep falls back to the model)
      return false;
    }
  } else if (targets_changed) {
    ws.RefreshTargets();
  }
  const double tolerance =
      kEnteringTolerance * std::max(1.0, ws.r.head(n).lpNorm<Eigen::Infinity>());
  // A residual past kAcceptResidual after the retry fails. Rows released from their hold go on
  // from the iterate, whose first pass (ShrinkToFeasible, not bounded by the budget) drops their
  // negative impulses.
  bool converged = RunActiveSetWithRetry(dt_s, tolerance);
  while (converged && ws.ReleaseRowsPullingPastTheirPush(dt_s))
    converged = RunActiveSetWithRetry(dt_s, tolerance);
  if (converged && !last_out_of_budget_ && !(last_residual_ <= kAcceptResidual)) converged = false;
  last_num_factorizations_ = ws.num_factorizations;
  if (!converged) {
    ws.n = -1;  // recompute everything next time
    last_residual_ = 0.0;
    return false;
  }
  ws.x.head(n) /= dt_s;  // λ = x/Δt
  last_num_active_ = static_cast<int>((ws.x.head(n).array() != 0.0).count());
  *F_c_N = ws.U.topLeftCorner(n, 3).transpose() * ws.x.head(n);
  *T_c_N_m = ws.U.topRightCorner(n, 3).transpose() * ws.x.head(n);
  last_solved_ = true;
  return true;
}

}  // namespace hapsim::contact
