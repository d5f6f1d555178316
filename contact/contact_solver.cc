#include "contact/contact_solver.h"

#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "contact/frame_friction_solver.h"
#include "core/error.h"

namespace hapsim::contact {
namespace {

ContactSolveReport SolveEquality(const Eigen::MatrixXd& W, const Eigen::VectorXd& rhs, double dt_s,
                                 double compliance, Eigen::VectorXd* lambda) {
  ContactSolveReport report;
  // Δt (W + ε diag W) λ = rhs: a compliance ε W_ii in series with each row (constraint force
  // mixing). Nearly redundant rows, to which the exact solve (ε = 0) gives large forces of both
  // signs that nearly cancel, then share their load (contact_solver.h says why).
  Eigen::MatrixXd A = dt_s * W;
  AddEqualityCompliance(compliance, &A);
  // Rank-revealing, as at ε = 0 redundant contacts (one body point twice, or many on a rigid
  // part) make W singular; the minimum-norm λ then shares the load between them.
  *lambda = Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(A).solve(rhs);
  const double rhs_norm = rhs.norm();
  report.residual = rhs_norm > 0.0 ? (A * *lambda - rhs).norm() / rhs_norm : 0.0;
  report.converged = lambda->allFinite();
  return report;
}

// Complementarity residual of the normal rows, max_i |min(λ_i, c_i / (Δt W_ii))|, in impulse
// units, relative to the largest |λ| (or absolute when λ = 0). Reads W only by the columns of the
// rows with λ ≠ 0, and its diagonal.
// A bilateral row's only condition is c_i = 0: its term is |c_i / (Δt W_ii)|.
double CalcNormalResidual(const Eigen::MatrixXd& W, const Eigen::VectorXd& W_diagonal,
                          const Eigen::VectorXd& rhs, double dt_s, const Eigen::VectorXd& lambda,
                          const std::vector<std::uint8_t>* bilateral) {
  Eigen::VectorXd c = -rhs;
  for (Eigen::Index col = 0; col < lambda.size(); ++col)
    if (lambda[col] != 0.0) c.noalias() += (dt_s * lambda[col]) * W.col(col);
  double residual = 0.0;
  for (Eigen::Index row = 0; row < lambda.size(); ++row) {
    const double slack = c[row] / (dt_s * W_diagonal[row]);
    const bool equality = bilateral && (*bilateral)[static_cast<size_t>(row)];
    residual = std::max(residual, std::abs(equality ? slack : std::min(lambda[row], slack)));
  }
  const double scale = lambda.lpNorm<Eigen::Infinity>();
  return scale > 0.0 ? residual / scale : residual;
}

}  // namespace

Eigen::Vector2d ProjectOntoDisc(const Eigen::Vector2d& lambda_t, double radius) {
  const double norm = lambda_t.norm();
  return norm > radius ? Eigen::Vector2d((norm > 0.0 ? radius / norm : 0.0) * lambda_t) : lambda_t;
}

Eigen::Vector2d StepTangentialImpulse(const Eigen::Vector2d& lambda_t, const Eigen::Vector2d& c_t,
                                      const Eigen::Matrix2d& W_tt, double dt_s, double radius) {
  const double omega = std::max(W_tt(0, 0), W_tt(1, 1)) + 0.5 * std::abs(W_tt(0, 1) + W_tt(1, 0));
  if (!(radius > 0.0) || !(omega > 0.0)) return Eigen::Vector2d::Zero();
  return ProjectOntoDisc(lambda_t - c_t / (dt_s * omega), radius);
}

double CalcFrictionResidual(const Eigen::MatrixXd& W, const Eigen::VectorXd& rhs, double dt_s,
                            double mu, const Eigen::VectorXd* mu_per_contact,
                            const Eigen::VectorXd& lambda) {
  const Eigen::VectorXd c = dt_s * W * lambda - rhs;
  double residual = 0.0;
  for (Eigen::Index normal = 0; normal < lambda.size(); normal += 3) {
    const double mu_contact = mu_per_contact ? (*mu_per_contact)[normal / 3] : mu;
    const Eigen::Vector2d lambda_t = lambda.segment<2>(normal + 1);
    const Eigen::Vector2d moved = StepTangentialImpulse(lambda_t, c.segment<2>(normal + 1),
                                                        W.block<2, 2>(normal + 1, normal + 1), dt_s,
                                                        mu_contact * lambda[normal]);
    residual = std::max({residual,
                         std::abs(std::min(lambda[normal], c[normal] / (dt_s * W(normal, normal)))),
                         (moved - lambda_t).norm()});
  }
  const double scale = lambda.lpNorm<Eigen::Infinity>();
  return scale > 0.0 ? residual / scale : residual;
}

namespace {

// Projected Gauss–Seidel. For each contact: the normal row gets λ_n ← max(0, λ_n − r_n/(ΔtW_nn));
// then the tangent pair moves together by one step against its residual and is
// projected onto the disc of radius μ λ_n (Jean & Moreau's non-smooth contact dynamics, in its
// simplest blocked form):
//   λ_t ← Proj_{|·| ≤ μλ_n}(λ_t − r_t / (Δt ω))   (StepTangentialImpulse).
// One step size for both tangents is what makes the fixed point Coulomb's law: inside the disc
// r_t = 0 (stick); on its rim r_t = −k λ_t with k > 0, friction opposite the sliding velocity.
// (Relaxing the two rows each by its own diagonal, as this solver once did, leaves a fixed point
// with λ_t ∥ −diag(W_tt)⁻¹ r_t, not opposite the slip when W_t1t1 ≠ W_t2t2.) The residual is
// CalcFrictionResidual's, so the tangential part is converged too, not only the normal rows.
ContactSolveReport SolveProjectedGaussSeidel(const Eigen::MatrixXd& W, const Eigen::VectorXd& rhs,
                                             double dt_s, double mu,
                                             const Eigen::VectorXd* mu_per_contact,
                                             const ContactSolveOptions& options,
                                             Eigen::VectorXd* lambda) {
  ContactSolveReport report;
  const Eigen::Index rows = rhs.size();
  // Wᵀ, so that a row of W is contiguous in memory (W is column-major and, with a rotating
  // tool, not symmetric).
  const Eigen::MatrixXd W_rows = W.transpose();
  for (report.iterations = 1; report.iterations <= options.max_iterations; ++report.iterations) {
    for (Eigen::Index normal = 0; normal < rows; normal += 3) {
      // Residual of the normal row of ΔtWλ = rhs, solved for λ_n with the others fixed.
      const double r_n = dt_s * W_rows.col(normal).dot(*lambda) - rhs[normal];
      (*lambda)[normal] = std::max(0.0, (*lambda)[normal] - r_n / (dt_s * W(normal, normal)));
      const double mu_contact = mu_per_contact ? (*mu_per_contact)[normal / 3] : mu;
      const Eigen::Vector2d r_t(dt_s * W_rows.col(normal + 1).dot(*lambda) - rhs[normal + 1],
                                dt_s * W_rows.col(normal + 2).dot(*lambda) - rhs[normal + 2]);
      lambda->segment<2>(normal + 1) = StepTangentialImpulse(lambda->segment<2>(normal + 1), r_t,
                                                             W.block<2, 2>(normal + 1, normal + 1),
                                                             dt_s, mu_contact * (*lambda)[normal]);
    }
    report.residual = CalcFrictionResidual(W, rhs, dt_s, mu, mu_per_contact, *lambda);
    if (report.residual <= options.tolerance) {
      report.converged = true;
      break;
    }
  }
  report.iterations = std::min(report.iterations, options.max_iterations);
  return report;
}

// M = Δt W + σ I of the active-set method below, read by columns: the method reads only the
// columns of its free rows, so W need hold no other (ColumnFiller fills them as rows enter). The
// shift σ, a relative 1e-10 of the largest diagonal entry, keeps the free-set systems non-singular
// when contacts are redundant (same body point twice, many on a nearly rigid part): without it the
// solves return garbage there and the method cycles. It changes λ by ~1e-10 relative.
class DelassusColumns {
 public:
  DelassusColumns(const Eigen::MatrixXd& W, const Eigen::VectorXd& W_diagonal, double dt_s)
      : W_(W), dt_s_(dt_s), shift_(1e-10 * dt_s * W_diagonal.cwiseAbs().maxCoeff()) {}
  // Entry (row, col): col's column must be filled.
  double operator()(Eigen::Index row, Eigen::Index col) const {
    return dt_s_ * W_(row, col) + (row == col ? shift_ : 0.0);
  }
  // *w += scale · M(:, col).
  void AddColumn(Eigen::Index col, double scale, Eigen::VectorXd* w) const {
    w->noalias() += (scale * dt_s_) * W_.col(col);
    (*w)[col] += scale * shift_;
  }

 private:
  const Eigen::MatrixXd& W_;
  const double dt_s_, shift_;
};

// The free rows of the active-set method below, and an LU factor of M restricted to them in
// the order they entered. M = ΔtW plus a small diagonal shift is not symmetric when the tool
// rotates (the coupling's torque Jacobian enters A_L), but its symmetric part is positive
// definite (W's is semidefinite; the shift makes it definite even for rigid contacts, whose W
// has rank 6), so every leading block's is too and LU needs no pivoting. Appending row e
// borders the factor in O(k²), two triangular solves:
//   [M_ff m_c; m_rᵀ M_ee] = [L 0; lᵀ 1] [U u; 0 δ],   L u = m_c,  Uᵀ l = m_r,  δ = M_ee − lᵀu.
// Rows leaving (the rarer event) rebuild it. Against refactoring M_ff by pivoted LU for every
// entering row, this takes block_press's frames (~210 rows, ~70 active) from 1.35 to ~0.3 ms.
// A pivot δ below 1e-8 M_ee (a row nearly dependent on the others: elimination without pivoting
// would amplify round-off) switches this solve to pivoted LU; on block_press and
// block_press_large the smallest δ / M_ee seen over 18,000 appends was 0.49 (a one-off count
// with a temporary print, 2026-11-25). Every entry it reads lies in a free row's column.
class FreeSet {
 public:
  // Rows marked in `bilateral` (may be null: none) are equalities: they never leave.
  FreeSet(const DelassusColumns& M, Eigen::Index n, const std::vector<std::uint8_t>* bilateral)
      : M_(M), LU_(n, n), is_free_(n, false), bilateral_(bilateral) {}

  const std::vector<Eigen::Index>& rows() const { return rows_; }
  bool contains(Eigen::Index row) const { return is_free_[row]; }
  bool is_bilateral(Eigen::Index row) const {
    return bilateral_ != nullptr && (*bilateral_)[static_cast<size_t>(row)] != 0;
  }

  void Add(Eigen::Index row) {
    factor_holds_ = factor_holds_ && Append(row);
    rows_.push_back(row);
    is_free_[row] = true;
  }

  // Adds `rows` to an empty set at once: the same factor as adding them one by one (up to
  // round-off), by blocks instead of bordering row by row (block_press's ~70 start rows: its
  // solve 0.25 → 0.22 ms a frame, docs/BENCHMARKS.md "eighth pass").
  void AddAll(const std::vector<Eigen::Index>& rows) {
    HAPSIM_INVARIANT(rows_.empty());
    for (Eigen::Index row : rows) {
      rows_.push_back(row);
      is_free_[row] = true;
    }
    const Eigen::Index k = static_cast<Eigen::Index>(rows_.size());
    Eigen::Block<Eigen::MatrixXd> F = LU_.topLeftCorner(k, k);
    for (Eigen::Index b = 0; b < k; ++b)
      for (Eigen::Index a = 0; a < k; ++a) F(a, b) = M_(rows_[a], rows_[b]);
    factor_holds_ = FactorWithoutPivoting(F);
  }

  // Unilateral rows whose λ is no longer positive leave (their λ set to exactly 0).
  void RemoveNonPositive(Eigen::VectorXd* lambda) {
    std::vector<Eigen::Index> kept;
    for (Eigen::Index row : rows_) {
      if ((*lambda)[row] > 0.0 || is_bilateral(row)) {
        kept.push_back(row);
      } else {
        (*lambda)[row] = 0.0;
        is_free_[row] = false;
      }
    }
    rows_.clear();
    AddAll(kept);
  }

  // z = M_ff⁻¹ rhs_f, rhs_f the free rows' entries of rhs, in the order of rows().
  Eigen::VectorXd Solve(const Eigen::VectorXd& rhs) const {
    const Eigen::Index k = static_cast<Eigen::Index>(rows_.size());
    Eigen::VectorXd z(k);
    for (Eigen::Index a = 0; a < k; ++a) z[a] = rhs[rows_[a]];
    if (factor_holds_) {
      LU_.topLeftCorner(k, k).triangularView<Eigen::UnitLower>().solveInPlace(z);
      LU_.topLeftCorner(k, k).triangularView<Eigen::Upper>().solveInPlace(z);
      return z;
    }
    Eigen::MatrixXd M_ff(k, k);
    for (Eigen::Index a = 0; a < k; ++a)
      for (Eigen::Index b = 0; b < k; ++b) M_ff(a, b) = M_(rows_[a], rows_[b]);
    return M_ff.partialPivLu().solve(z);
  }

 private:
  // Borders the factor of rows_ with `row`; false, the factor unchanged, at a tiny pivot.
  bool Append(Eigen::Index row) {
    const Eigen::Index k = static_cast<Eigen::Index>(rows_.size());
    Eigen::VectorXd u(k), l(k);
    for (Eigen::Index a = 0; a < k; ++a) {
      u[a] = M_(rows_[a], row);
      l[a] = M_(row, rows_[a]);
    }
    LU_.topLeftCorner(k, k).triangularView<Eigen::UnitLower>().solveInPlace(u);
    LU_.topLeftCorner(k, k).triangularView<Eigen::Upper>().transpose().solveInPlace(l);
    const double delta = M_(row, row) - l.dot(u);
    if (!(delta > 1e-8 * M_(row, row))) return false;
    LU_.row(k).head(k) = l.transpose();
    LU_.col(k).head(k) = u;
    LU_(k, k) = delta;
    return true;
  }

  // LU without pivoting of F = M over rows_, in place, right-looking by blocks of 16 columns: a
  // panel's columns one by one, then the block row right of it (a unit-lower triangular solve)
  // and the trailing block (one matrix product). Its pivots are the Schur complements that
  // Append's δ are, so it fails where some Append would: at a pivot ≤ 1e-8 M(row, row).
  bool FactorWithoutPivoting(Eigen::Block<Eigen::MatrixXd> F) const {
    constexpr Eigen::Index kBlock = 16;
    const Eigen::Index n = F.rows();
    for (Eigen::Index j0 = 0; j0 < n; j0 += kBlock) {
      const Eigen::Index width = std::min(kBlock, n - j0), rest = n - j0 - width;
      for (Eigen::Index j = j0; j < j0 + width; ++j) {
        const double pivot = F(j, j);
        if (!(pivot > 1e-8 * M_(rows_[j], rows_[j]))) return false;
        const Eigen::Index below = n - j - 1, right = j0 + width - j - 1;
        F.col(j).tail(below) /= pivot;
        F.block(j + 1, j + 1, below, right).noalias() -=
            F.col(j).tail(below) * F.row(j).segment(j + 1, right);
      }
      if (rest == 0) break;
      F.block(j0, j0, width, width)
          .triangularView<Eigen::UnitLower>()
          .solveInPlace(F.block(j0, j0 + width, width, rest));
      F.block(j0 + width, j0 + width, rest, rest).noalias() -=
          F.block(j0 + width, j0, rest, width) * F.block(j0, j0 + width, width, rest);
    }
    return true;
  }

  const DelassusColumns& M_;
  Eigen::MatrixXd LU_;  // L below the diagonal (unit diagonal implied), U on and above it
  std::vector<Eigen::Index> rows_;
  std::vector<bool> is_free_;
  const std::vector<std::uint8_t>* bilateral_;
  bool factor_holds_ = true;  // LU_ is the factor of M over rows_ (else: pivoted LU per solve)
};

// Moves the free rows' λ from where they are toward z (the equality solution on the free set),
// as far as every unilateral λ stays ≥ 0 (the ratio test; a bilateral row's λ has no sign).
// Returns false if a row hit zero on the way.
bool StepToward(const Eigen::VectorXd& z, const FreeSet& free_set, Eigen::VectorXd* lambda) {
  const std::vector<Eigen::Index>& free_rows = free_set.rows();
  const Eigen::Index k = z.size();
  double step = 1.0;
  Eigen::Index limiting = -1;
  for (Eigen::Index a = 0; a < k; ++a) {
    const double current = (*lambda)[free_rows[a]];
    if (free_set.is_bilateral(free_rows[a])) continue;
    if (z[a] <= 0.0 && current / (current - z[a]) < step) {
      step = current / (current - z[a]);
      limiting = a;
    }
  }
  for (Eigen::Index a = 0; a < k; ++a)
    (*lambda)[free_rows[a]] += step * (z[a] - (*lambda)[free_rows[a]]);
  if (limiting < 0) return true;
  // The row that limited the step is exactly at zero by construction; round-off can leave it
  // a hair above, and then it would never leave and the loop would not end.
  (*lambda)[free_rows[limiting]] = 0.0;
  return false;
}

// Frictionless unilateral contact as the convex QP  min ½ λᵀ(ΔtW)λ − rhsᵀλ  s.t. λ ≥ 0, whose
// optimality conditions are the LCP. Primal active-set method in the manner of Lawson & Hanson's
// NNLS: add the most violated row to the free set, solve the equality on the free set, and step
// back along the segment (ratio test) when a free λ would turn negative. Finite and exact to
// round-off, unlike Gauss–Seidel, which crawls when many contacts are nearly redundant (a stiff
// body under a flat tool: W is close to the rank-6 tool part).
// Started from a λ ≥ 0 (the last frame's, ImpulseWarmStart), its positive rows form the first free
// set: the method only needs a feasible start whose positive rows are the free ones, and every
// step from there lowers the objective as from zero, so it ends at the LCP's solution as from
// zero (to the slack tolerance; see contact_solver.h on redundant rows). A press then enters its
// loaded rows in one go instead of one an iteration.
// Bilateral rows (a grasp's) make it the mixed problem with those λ unconstrained, still a convex
// QP: they are free from the start, whatever their λ, never leave and take no part in the ratio
// test, as equality constraints in an active-set QP method.
ContactSolveReport SolveActiveSet(const Eigen::MatrixXd& W, const Eigen::VectorXd& W_diagonal,
                                  const ColumnFiller& fill_columns, const Eigen::VectorXd& rhs,
                                  double dt_s, const ContactSolveOptions& options,
                                  const std::vector<std::uint8_t>* bilateral,
                                  Eigen::VectorXd* lambda) {
  const Eigen::Index n = rhs.size();
  const DelassusColumns M(W, W_diagonal, dt_s);
  const double tolerance = options.tolerance * std::max(1.0, rhs.lpNorm<Eigen::Infinity>());
  FreeSet free_set(M, n, bilateral);
  std::vector<Eigen::Index> start;
  for (Eigen::Index i = 0; i < n; ++i) {
    if ((*lambda)[i] > 0.0 || free_set.is_bilateral(i))
      start.push_back(i);
    else
      (*lambda)[i] = 0.0;
  }
  if (fill_columns) fill_columns(start);
  free_set.AddAll(start);
  // The equality on the free rows, stepping back while a free λ would turn negative. Then w, the
  // slack: only free rows carry λ, so O(n k), not O(n²).
  Eigen::VectorXd w(n);
  const auto solve_free_set = [&] {
    while (!free_set.rows().empty() && !StepToward(free_set.Solve(rhs), free_set, lambda))
      free_set.RemoveNonPositive(lambda);
    w = -rhs;  // w = Mλ − rhs
    for (Eigen::Index row : free_set.rows()) M.AddColumn(row, (*lambda)[row], &w);
  };
  solve_free_set();
  ContactSolveReport report;
  for (; report.iterations < 3 * n + 10; ++report.iterations) {
    Eigen::Index entering = -1;
    double most_violated = -tolerance;
    for (Eigen::Index i = 0; i < n; ++i)
      if (!free_set.contains(i) && w[i] < most_violated) most_violated = w[i], entering = i;
    if (entering < 0) break;
    if (fill_columns) fill_columns({entering});
    free_set.Add(entering);
    solve_free_set();
  }
  report.residual = CalcNormalResidual(W, W_diagonal, rhs, dt_s, *lambda, bilateral);
  report.converged = report.residual <= std::max(options.tolerance, 1e-9);
  return report;
}

}  // namespace

void AddEqualityCompliance(double equality_compliance, Eigen::MatrixXd* W) {
  W->diagonal() *= 1.0 + equality_compliance;
}

const char* ToString(ContactLaw law) {
  switch (law) {
    case ContactLaw::kEquality:
      return "equality";
    case ContactLaw::kUnilateral:
      return "unilateral";
    case ContactLaw::kFriction:
      return "friction";
  }
  return "unknown";
}

ContactSolveReport SolveContactImpulses(const Eigen::MatrixXd& W, const Eigen::VectorXd& rhs,
                                        double dt_s, int rows_per_contact,
                                        const ContactSolveOptions& options, Eigen::VectorXd* lambda,
                                        const Eigen::VectorXd* friction_per_contact,
                                        const std::vector<std::uint8_t>* bilateral_rows) {
  if (W.rows() != rhs.size() || W.cols() != rhs.size())
    throw std::invalid_argument("W must be square with one row per constraint row");
  if (bilateral_rows && static_cast<Eigen::Index>(bilateral_rows->size()) != rhs.size())
    throw std::invalid_argument("bilateral_rows needs one entry per constraint row");
  const bool any_bilateral =
      bilateral_rows && std::any_of(bilateral_rows->begin(), bilateral_rows->end(),
                                    [](std::uint8_t b) { return b != 0; });
  if (any_bilateral && options.law == ContactLaw::kFriction)
    throw std::invalid_argument("bilateral rows are not supported with the friction law");
  if (!(options.equality_compliance >= 0.0 && std::isfinite(options.equality_compliance)))
    throw std::invalid_argument("equality_compliance must be finite and >= 0");
  if (friction_per_contact && friction_per_contact->size() * rows_per_contact != rhs.size())
    throw std::invalid_argument("friction_per_contact needs one μ per contact");
  if (lambda->size() != rhs.size()) lambda->setZero(rhs.size());
  if (rhs.size() == 0) return ContactSolveReport{0, 0.0, true};
  switch (options.law) {
    case ContactLaw::kEquality:
      return SolveEquality(W, rhs, dt_s, options.equality_compliance, lambda);
    case ContactLaw::kUnilateral:
      if (rows_per_contact != 1)
        throw std::invalid_argument("unilateral contact uses normal rows only");
      return SolveActiveSet(W, W.diagonal(), nullptr, rhs, dt_s, options,
                            any_bilateral ? bilateral_rows : nullptr, lambda);
    case ContactLaw::kFriction:
      if (rows_per_contact != 3) throw std::invalid_argument("friction needs 3 rows per contact");
      if (options.friction_method == FrictionMethod::kDenseGaussSeidel)
        return SolveProjectedGaussSeidel(W, rhs, dt_s, options.friction_coefficient,
                                         friction_per_contact, options, lambda);
      return SolveFrictionOnWorkingSet(
          W, rhs, dt_s,
          friction_per_contact
              ? *friction_per_contact
              : Eigen::VectorXd::Constant(rhs.size() / 3, options.friction_coefficient),
          options, lambda);
  }
  throw std::invalid_argument("unknown contact law");
}

ContactSolveReport SolveUnilateralByColumns(
    const Eigen::MatrixXd& W, const Eigen::VectorXd& W_diagonal, const ColumnFiller& fill_columns,
    const Eigen::VectorXd& rhs, double dt_s, const ContactSolveOptions& options,
    Eigen::VectorXd* lambda, const std::vector<std::uint8_t>* bilateral_rows) {
  if (W.rows() != rhs.size() || W.cols() != rhs.size() || W_diagonal.size() != rhs.size())
    throw std::invalid_argument("W must be square and its diagonal hold one entry per row");
  if (bilateral_rows && static_cast<Eigen::Index>(bilateral_rows->size()) != rhs.size())
    throw std::invalid_argument("bilateral_rows needs one entry per constraint row");
  if (options.law != ContactLaw::kUnilateral)
    throw std::invalid_argument("SolveUnilateralByColumns solves the unilateral law only");
  if (lambda->size() != rhs.size()) lambda->setZero(rhs.size());
  if (rhs.size() == 0) return ContactSolveReport{0, 0.0, true};
  return SolveActiveSet(W, W_diagonal, fill_columns, rhs, dt_s, options, bilateral_rows, lambda);
}

}  // namespace hapsim::contact
