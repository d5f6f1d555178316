#include "contact/frame_friction_solver.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

// LAPACK (the system's, OpenBLAS on Debian; CHOLMOD links it too): LU with partial pivoting and
// its solve. At the ~210 rows of block_press_friction's Newton steps dgetrf takes about half of
// Eigen's PartialPivLU (0.28 against 0.54 ms on the host of the measurements, which has no
// Eigen build for wider than SSE2).
extern "C" void dgetrf_(const int* m, const int* n, double* a, const int* lda, int* ipiv,
                        int* info);
extern "C" void dgetrs_(const char* trans, const int* n, const int* nrhs, const double* a,
                        const int* lda, const int* ipiv, double* b, const int* ldb, int* info);

namespace hapsim::contact {
namespace {

// The kept c drifts from M x − rhs by round-off in each column update; it is recomputed from M
// this often (a product costs about what one sweep does), and always before the solve ends.
constexpr int kSweepsBetweenRecompute = 50;
// Contacts that have left the set's load (λ = 0, c_n ≥ 0) are dropped after a sweep that leaves
// at least this fraction of the set so (block_press_friction: ~2/3 of the contacts that approach
// at the start are separated again after the first sweep).
constexpr double kCompactionFraction = 0.25;
// ... counting only contacts separated after this many sweeps in a row: one dropped too early
// (released in one sweep, loaded again a few later) costs another solve of the set once it is
// found approaching.
constexpr int kSeparatedSweepsBeforeDrop = 3;
// Sweeps with no contact changing state (separated, sticking, sliding) before a Newton step;
// doubled after a Newton step that did not lower the residual.
constexpr int kStableSweepsBeforeNewton = 4;
// A contact is sliding when |λ_t| ≥ (1 − this) μλ_n (the sweep's projection puts it on the rim
// to round-off).
constexpr double kRimTolerance = 1e-9;

enum class State : char { kSeparated, kSticking, kSliding };

// The friction problem restricted to a working set of contacts, gathered contiguously: x = λ_S,
// c = M x − rhs_S with M = Δt W_SS.
class WorkingSet {
 public:
  WorkingSet(const Eigen::MatrixXd& W, const Eigen::VectorXd& rhs, double dt_s,
             const Eigen::VectorXd& mu)
      : W_(W), rhs_(rhs), dt_s_(dt_s), mu_(mu) {}

  // Takes the contacts (indices into the full problem) and their impulses from `lambda` (full).
  void Gather(const std::vector<int>& contacts, const Eigen::VectorXd& lambda);
  // Writes the set's impulses into `lambda` (full); the others are left as they are.
  void Scatter(Eigen::VectorXd* lambda) const;
  const std::vector<int>& contacts() const { return contacts_; }
  // Sweeps and Newton steps until the relative residual is ≤ tolerance or max_sweeps sweeps
  // are done. Returns the sweeps done; *residual receives the residual of the returned iterate
  // (a sweep's: admissible), *newton_steps is incremented per Newton step.
  int Solve(int max_sweeps, double tolerance, double* residual, int* newton_steps);

 private:
  Eigen::Index size() const { return static_cast<Eigen::Index>(contacts_.size()); }
  void RecomputeVelocity() {
    c_.head(3 * size()).noalias() = M_.topLeftCorner(3 * size(), 3 * size()) * x_.head(3 * size());
    c_.head(3 * size()) -= r_.head(3 * size());
  }
  // One sweep; returns whether any contact changed state.
  bool Sweep();
  State CalcState(Eigen::Index j) const;
  // Drops the contacts with λ = 0 and c_n ≥ 0 (for kSeparatedSweepsBeforeDrop sweeps), in
  // place, if they are kCompactionFraction of the set or more.
  void Compact();
  // CalcFrictionResidual's measure over the set, from the kept c.
  double CalcResidual() const;
  // Whether contact j has friction: μ > 0 and a tangential block whose step size is positive
  // (StepTangentialImpulse's condition).
  bool CarriesFriction(Eigen::Index j) const;
  enum class Law : char { kSticking, kSliding, kNoFriction };
  Law CalcLaw(Eigen::Index j) const;  // which of Newton's equations a loaded contact has
  Eigen::Vector3d CalcNewtonResidual(Eigen::Index j) const;
  void SetNewtonRows(Eigen::Index j, Eigen::Index row, Eigen::Index m);
  bool NewtonStep(bool allow_reuse, bool* reused);
  bool TryNewton(double* residual, int* sweeps, int* newton_steps);

  const Eigen::MatrixXd& W_;
  const Eigen::VectorXd& rhs_;
  const double dt_s_;
  const Eigen::VectorXd& mu_;  // per contact of the full problem
  std::vector<int> contacts_;
  std::vector<Eigen::Matrix3d> W_blocks_;  // W's 3 × 3 diagonal block of each set contact
  std::vector<State> state_;               // after the last sweep
  std::vector<int> separated_for_;         // sweeps each contact has ended separated in a row
  Eigen::MatrixXd M_;                      // Δt W over the set's rows (3k × 3k, top left)
  Eigen::VectorXd r_, x_, c_;              // rhs, λ and c over the set's rows
  Eigen::VectorXd x_saved_, c_saved_;      // before a Newton step
  std::vector<State> state_saved_;
  Eigen::MatrixXd J_;                 // the Newton step's Jacobian (top left)
  Eigen::VectorXd G_, step_;          // and its residual and step
  std::vector<Eigen::Index> keep_;    // Compact's scratch
  std::vector<Eigen::Index> loaded_;  // the step's contacts (λ_n > 0) and their laws
  std::vector<Law> loaded_laws_;
  // The last Jacobian's LU factor (in J_, dgetrf's layout, pivots in pivots_), for the contacts
  // and laws it was formed at.
  std::vector<int> pivots_;
  std::vector<Eigen::Index> factor_loaded_;
  std::vector<Law> factor_laws_;
  bool factor_holds_ = false;
};

void WorkingSet::Gather(const std::vector<int>& contacts, const Eigen::VectorXd& lambda) {
  contacts_ = contacts;
  const Eigen::Index k = size();
  M_.resize(3 * k, 3 * k);
  r_.resize(3 * k);
  x_.resize(3 * k);
  W_blocks_.resize(contacts_.size());
  state_.assign(contacts_.size(), State::kSeparated);
  separated_for_.assign(contacts_.size(), 0);
  for (Eigen::Index b = 0; b < k; ++b) {
    const Eigen::Index col = 3 * contacts_[b];
    for (Eigen::Index a = 0; a < k; ++a)
      M_.block<3, 3>(3 * a, 3 * b) = dt_s_ * W_.block<3, 3>(3 * contacts_[a], col);
    W_blocks_[b] = W_.block<3, 3>(col, col);
    r_.segment<3>(3 * b) = rhs_.segment<3>(col);
    x_.segment<3>(3 * b) = lambda.segment<3>(col);
  }
  c_.resize(3 * k);
  x_saved_.resize(3 * k);
  c_saved_.resize(3 * k);
  G_.resize(3 * k);
  step_.resize(3 * k);
  J_.resize(3 * k, 3 * k);
  factor_holds_ = false;
}

void WorkingSet::Scatter(Eigen::VectorXd* lambda) const {
  for (size_t b = 0; b < contacts_.size(); ++b)
    lambda->segment<3>(3 * contacts_[b]) = x_.segment<3>(3 * b);
}

State WorkingSet::CalcState(Eigen::Index j) const {
  const double normal = x_[3 * j];
  if (!(normal > 0.0)) return State::kSeparated;
  return x_.segment<2>(3 * j + 1).norm() >= (1.0 - kRimTolerance) * mu_[contacts_[j]] * normal
             ? State::kSliding
             : State::kSticking;
}

// One blocked projected Gauss–Seidel sweep, SolveContactImpulses' (contact_solver.cc) with c
// kept by columns: per contact the normal row, then the tangent pair against the normal's new
// impulse. A contact at λ = 0 whose normal velocity is not negative stays there (the dense sweep
// would leave it too: λ_n stays 0 and a disc of radius 0 moves nothing).
bool WorkingSet::Sweep() {
  bool changed = false;
  for (Eigen::Index j = 0; j < size(); ++j) {
    const Eigen::Index a = 3 * j;
    const Eigen::Vector3d old = x_.segment<3>(a);
    const Eigen::Matrix3d& W_jj = W_blocks_[j];
    if ((old.isZero(0.0) && c_[a] >= 0.0) || !(W_jj(0, 0) > 0.0)) {
      // Separated and staying so; or no normal compliance: no step exists.
      changed = changed || state_[j] != State::kSeparated;
      state_[j] = State::kSeparated;
      ++separated_for_[j];
      continue;
    }
    Eigen::Vector3d c = c_.segment<3>(a);
    Eigen::Vector3d next;
    next[0] = std::max(0.0, old[0] - c[0] / (dt_s_ * W_jj(0, 0)));
    c.tail<2>() += dt_s_ * W_jj.block<2, 1>(1, 0) * (next[0] - old[0]);
    next.tail<2>() = StepTangentialImpulse(old.tail<2>(), c.tail<2>(), W_jj.block<2, 2>(1, 1),
                                           dt_s_, mu_[contacts_[j]] * next[0]);
    const Eigen::Vector3d delta = next - old;
    if (!delta.isZero(0.0)) {
      x_.segment<3>(a) = next;
      c_.head(3 * size()).noalias() += M_.block(0, a, 3 * size(), 3) * delta;
    }
    const State state = CalcState(j);
    changed = changed || state != state_[j];
    state_[j] = state;
    separated_for_[j] = state == State::kSeparated ? separated_for_[j] + 1 : 0;
  }
  return changed;
}

void WorkingSet::Compact() {
  Eigen::Index kept = 0;
  keep_.clear();
  for (Eigen::Index j = 0; j < size(); ++j)
    if (!(x_.segment<3>(3 * j).isZero(0.0) && c_[3 * j] >= 0.0 &&
          separated_for_[j] >= kSeparatedSweepsBeforeDrop))
      keep_.push_back(j);
  const std::vector<Eigen::Index>& keep = keep_;
  if (static_cast<double>(size() - static_cast<Eigen::Index>(keep.size())) <
      std::max(1.0, kCompactionFraction * static_cast<double>(size())))
    return;
  // In place: every destination index is at most its source, so nothing is overwritten before
  // it is read (columns in order, and within a column rows in order).
  for (Eigen::Index b = 0; b < static_cast<Eigen::Index>(keep.size()); ++b) {
    for (Eigen::Index a = 0; a < static_cast<Eigen::Index>(keep.size()); ++a)
      M_.block<3, 3>(3 * a, 3 * b) = M_.block<3, 3>(3 * keep[a], 3 * keep[b]);
  }
  for (Eigen::Index j : keep) {
    contacts_[kept] = contacts_[j];
    W_blocks_[kept] = W_blocks_[j];
    state_[kept] = state_[j];
    separated_for_[kept] = separated_for_[j];
    r_.segment<3>(3 * kept) = r_.segment<3>(3 * j);
    x_.segment<3>(3 * kept) = x_.segment<3>(3 * j);
    c_.segment<3>(3 * kept) = c_.segment<3>(3 * j);
    ++kept;
  }
  contacts_.resize(kept);
  W_blocks_.resize(kept);
  state_.resize(kept);
  separated_for_.resize(kept);
  factor_holds_ = false;  // its contacts' indices in the set have moved
}

double WorkingSet::CalcResidual() const {
  double residual = 0.0;
  for (Eigen::Index j = 0; j < size(); ++j) {
    const Eigen::Index a = 3 * j;
    const Eigen::Matrix3d& W_jj = W_blocks_[j];
    const Eigen::Vector2d lambda_t = x_.segment<2>(a + 1);
    const Eigen::Vector2d moved = StepTangentialImpulse(
        lambda_t, c_.segment<2>(a + 1), W_jj.block<2, 2>(1, 1), dt_s_, mu_[contacts_[j]] * x_[a]);
    residual = std::max({residual, std::abs(std::min(x_[a], c_[a] / (dt_s_ * W_jj(0, 0)))),
                         (moved - lambda_t).norm()});
  }
  const double scale = x_.head(3 * size()).lpNorm<Eigen::Infinity>();
  return scale > 0.0 ? residual / scale : residual;
}

bool WorkingSet::CarriesFriction(Eigen::Index j) const {
  // StepTangentialImpulse's condition: no friction where its step size would not be positive.
  const Eigen::Matrix3d& W_jj = W_blocks_[j];
  return mu_[contacts_[j]] > 0.0 &&
         std::max(W_jj(1, 1), W_jj(2, 2)) + 0.5 * std::abs(W_jj(1, 2) + W_jj(2, 1)) > 0.0;
}

// Newton's equations for loaded contact j (NewtonStep), G_j:
//   sticking      c_n = 0, c_t = 0
//   sliding       c_n = 0, |λ_t| − μλ_n = 0, c_t1 λ_t2 − c_t2 λ_t1 = 0 (c_t ∥ λ_t)
//   no friction   c_n = 0, λ_t = 0
// The sliding pair is smooth where λ_t ≠ 0 (μλ_n > 0), unlike λ_t + μλ_n c_t/|c_t|, which
// divides by a slip that vanishes at the stick–slip boundary. c_t's sign against λ_t is left to
// the sweep after the step.
WorkingSet::Law WorkingSet::CalcLaw(Eigen::Index j) const {
  if (!CarriesFriction(j)) return Law::kNoFriction;
  return state_[j] == State::kSliding ? Law::kSliding : Law::kSticking;
}

Eigen::Vector3d WorkingSet::CalcNewtonResidual(Eigen::Index j) const {
  const Eigen::Index a = 3 * j;
  switch (CalcLaw(j)) {
    case Law::kSticking:
      return c_.segment<3>(a);
    case Law::kSliding: {
      const Eigen::Vector2d t = x_.segment<2>(a + 1), c_t = c_.segment<2>(a + 1);
      return {c_[a], t.norm() - mu_[contacts_[j]] * x_[a], c_t[0] * t[1] - c_t[1] * t[0]};
    }
    case Law::kNoFriction:
      break;
  }
  return {c_[a], x_[a + 1], x_[a + 2]};
}

// Rows 3l..3l+2 of J = ∂G/∂x over the loaded contacts' impulses for loaded contact j; on entry
// they hold M's rows of the contact (c's derivative), which the sticking law keeps.
void WorkingSet::SetNewtonRows(Eigen::Index j, Eigen::Index row, Eigen::Index m) {
  const Eigen::Index a = 3 * j;
  switch (CalcLaw(j)) {
    case Law::kSticking:
      return;
    case Law::kSliding: {
      const Eigen::Vector2d t = x_.segment<2>(a + 1), c_t = c_.segment<2>(a + 1);
      J_.row(row + 2).head(m) = t[1] * J_.row(row + 1).head(m) - t[0] * J_.row(row + 2).head(m);
      J_(row + 2, row + 1) -= c_t[1];
      J_(row + 2, row + 2) += c_t[0];
      J_.row(row + 1).head(m).setZero();
      J_(row + 1, row) = -mu_[contacts_[j]];
      J_.block<1, 2>(row + 1, row + 1) = t.transpose() / t.norm();
      return;
    }
    case Law::kNoFriction:
      break;
  }
  J_.block(row + 1, 0, 2, m).setZero();
  J_(row + 1, row + 1) = J_(row + 2, row + 2) = 1.0;
}

// A Newton step on the loaded contacts' equations (CalcNewtonResidual) with their states held:
// exact in one step for the sticking ones, quadratic for the sliding ones. With allow_reuse, the
// last step's factor serves if it was formed for the same contacts in the same states (a chord
// step: O(m²) instead of O(m³); *reused says so). c is recomputed after the step.
bool WorkingSet::NewtonStep(bool allow_reuse, bool* reused) {
  loaded_.clear();
  for (Eigen::Index j = 0; j < size(); ++j)
    if (state_[j] != State::kSeparated) loaded_.push_back(j);
  const Eigen::Index m = 3 * static_cast<Eigen::Index>(loaded_.size());
  *reused = false;
  if (m == 0) return false;
  loaded_laws_.clear();
  for (Eigen::Index j : loaded_) loaded_laws_.push_back(CalcLaw(j));
  *reused =
      allow_reuse && factor_holds_ && loaded_ == factor_loaded_ && loaded_laws_ == factor_laws_;
  if (!*reused) {
    for (Eigen::Index b = 0; b < m / 3; ++b)
      for (Eigen::Index a = 0; a < m / 3; ++a)
        J_.block<3, 3>(3 * a, 3 * b) = M_.block<3, 3>(3 * loaded_[a], 3 * loaded_[b]);
    for (Eigen::Index l = 0; l < m / 3; ++l) SetNewtonRows(loaded_[l], 3 * l, m);
    const int order = static_cast<int>(m), lda = static_cast<int>(J_.rows());
    int info = 0;
    pivots_.resize(m);
    factor_holds_ = false;
    dgetrf_(&order, &order, J_.data(), &lda, pivots_.data(), &info);
    if (info != 0) return false;  // singular (info > 0)
    factor_loaded_ = loaded_;
    factor_laws_ = loaded_laws_;
    factor_holds_ = true;
  }
  for (Eigen::Index l = 0; l < m / 3; ++l) G_.segment<3>(3 * l) = CalcNewtonResidual(loaded_[l]);
  step_.head(m) = G_.head(m);
  const int order = static_cast<int>(m), lda = static_cast<int>(J_.rows()), one = 1;
  int info = 0;
  dgetrs_("N", &order, &one, J_.data(), &lda, pivots_.data(), step_.data(), &order, &info);
  if (info != 0 || !step_.head(m).allFinite()) return false;
  for (Eigen::Index l = 0; l < m / 3; ++l) x_.segment<3>(3 * loaded_[l]) -= step_.segment<3>(3 * l);
  RecomputeVelocity();
  return true;
}

// Newton (NewtonStep), then a sweep, which makes the iterate admissible again. Kept if it lowers
// the residual; a chord step that does not is retried with a fresh factor; else undone.
bool WorkingSet::TryNewton(double* residual, int* sweeps, int* newton_steps) {
  const Eigen::Index rows = 3 * size();
  x_saved_.head(rows) = x_.head(rows);
  c_saved_.head(rows) = c_.head(rows);
  state_saved_ = state_;
  const double before = *residual;
  for (bool allow_reuse : {true, false}) {
    bool reused = false;
    ++*newton_steps;
    if (NewtonStep(allow_reuse, &reused)) {
      Sweep();
      ++*sweeps;
      *residual = CalcResidual();
      if (*residual < before) return true;
    }
    x_.head(rows) = x_saved_.head(rows);
    c_.head(rows) = c_saved_.head(rows);
    state_ = state_saved_;
    *residual = before;
    if (!reused) break;
  }
  factor_holds_ = false;
  return false;
}

int WorkingSet::Solve(int max_sweeps, double tolerance, double* residual, int* newton_steps) {
  RecomputeVelocity();
  *residual = CalcResidual();
  int sweeps = 0, stable = 0, wait = kStableSweepsBeforeNewton;
  while (sweeps < max_sweeps && !(*residual <= tolerance)) {
    const bool changed = Sweep();
    ++sweeps;
    Compact();
    if (sweeps % kSweepsBetweenRecompute == 0) RecomputeVelocity();
    *residual = CalcResidual();
    if (*residual <= tolerance) {  // confirmed on c recomputed: the kept sums may have drifted
      RecomputeVelocity();
      *residual = CalcResidual();
      continue;
    }
    stable = changed ? 0 : stable + 1;
    if (stable < wait || sweeps >= max_sweeps - 1) continue;
    if (TryNewton(residual, &sweeps, newton_steps)) {
      stable = wait - 1;  // one more stable sweep and the next step
    } else {
      wait *= 2;  // tried again after twice as many stable sweeps
      stable = 0;
    }
  }
  return sweeps;
}

// The contacts to start the set with: those that carry load or approach at the start.
std::vector<int> SelectStartingSet(const Eigen::VectorXd& lambda, const Eigen::VectorXd& c) {
  std::vector<int> contacts;
  for (Eigen::Index i = 0; 3 * i < lambda.size(); ++i)
    if (!lambda.segment<3>(3 * i).isZero(0.0) || c[3 * i] < 0.0)
      contacts.push_back(static_cast<int>(i));
  return contacts;
}

// Clamps a start into the admissible set: λ_n ≥ 0, |λ_t| ≤ μλ_n.
void MakeAdmissible(const Eigen::VectorXd& mu, Eigen::VectorXd* lambda) {
  for (Eigen::Index i = 0; i < mu.size(); ++i) {
    (*lambda)[3 * i] = std::max(0.0, (*lambda)[3 * i]);
    lambda->segment<2>(3 * i + 1) =
        ProjectOntoDisc(lambda->segment<2>(3 * i + 1), mu[i] * (*lambda)[3 * i]);
  }
}

}  // namespace

ContactSolveReport SolveFrictionOnWorkingSet(const Eigen::MatrixXd& W, const Eigen::VectorXd& rhs,
                                             double dt_s, const Eigen::VectorXd& mu,
                                             const ContactSolveOptions& options,
                                             Eigen::VectorXd* lambda) {
  const Eigen::Index n = rhs.size();
  if (W.rows() != n || W.cols() != n || n % 3 != 0 || mu.size() != n / 3)
    throw std::invalid_argument("SolveFrictionOnWorkingSet: W (n x n), rhs (n), mu (n / 3)");
  if (lambda->size() != n) lambda->setZero(n);
  MakeAdmissible(mu, lambda);
  ContactSolveReport report;
  // c over every row (λ is nonzero in the set's columns only, once the set is solved).
  Eigen::VectorXd c = -rhs;
  if (!lambda->isZero(0.0)) c.noalias() += dt_s * (W * *lambda);
  std::vector<int> set = SelectStartingSet(*lambda, c);
  std::vector<bool> in_set(n / 3, false);
  WorkingSet working_set(W, rhs, dt_s, mu);
  for (;;) {
    working_set.Gather(set, *lambda);
    report.iterations +=
        working_set.Solve(options.max_iterations - report.iterations, options.tolerance,
                          &report.residual, &report.newton_steps);
    for (int i : set) lambda->segment<3>(3 * i).setZero();  // those the set dropped stay 0
    working_set.Scatter(lambda);
    // The set as it ended (dropped contacts have λ = 0); the others' velocities with its
    // impulses; those that approach join it.
    set = working_set.contacts();
    c = -rhs;
    std::fill(in_set.begin(), in_set.end(), false);
    for (int i : set) {
      in_set[i] = true;
      c.noalias() += W.middleCols<3>(3 * i) * Eigen::Vector3d(dt_s * lambda->segment<3>(3 * i));
    }
    const double scale = lambda->lpNorm<Eigen::Infinity>();
    bool grew = false;
    for (Eigen::Index i = 0; i < n / 3; ++i) {
      if (in_set[i] || !(c[3 * i] < 0.0)) continue;
      // |min(λ_n, c_n/(ΔtW_nn))| with λ_n = 0 (the tangential term is 0: a disc of radius 0).
      const double violation = -c[3 * i] / (dt_s * W(3 * i, 3 * i));
      const double relative = scale > 0.0 ? violation / scale : violation;
      if (!(relative <= options.tolerance)) {
        set.push_back(static_cast<int>(i));
        grew = true;
      }
      report.residual = std::max(report.residual, relative);
    }
    if (!grew || report.iterations >= options.max_iterations) break;
    std::sort(set.begin(), set.end());
  }
  report.converged = report.residual <= options.tolerance;
  return report;
}

}  // namespace hapsim::contact
