#include "contact/contact_solver.h"

#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace hapsim::contact {
namespace {

ContactSolveReport SolveEquality(const Eigen::MatrixXd& W, const Eigen::VectorXd& rhs, double dt_s,
                                 Eigen::VectorXd* lambda) {
  ContactSolveReport report;
  // Rank-revealing, as redundant contacts (one body point twice, or many on a rigid part) make W
  // singular; the minimum-norm λ then shares the load between them.
  *lambda = Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(dt_s * W).solve(rhs);
  const double rhs_norm = rhs.norm();
  report.residual = rhs_norm > 0.0 ? (dt_s * W * *lambda - rhs).norm() / rhs_norm : 0.0;
  report.converged = lambda->allFinite();
  return report;
}

// Complementarity residual of the normal rows, max_i |min(λ_i, c_i / (Δt W_ii))|, in impulse
// units, relative to the largest |λ| (or absolute when λ = 0).
double CalcNormalResidual(const Eigen::MatrixXd& W, const Eigen::VectorXd& rhs, double dt_s,
                          int stride, const Eigen::VectorXd& lambda) {
  const Eigen::VectorXd c = dt_s * (W * lambda) - rhs;  // by columns: W is column-major
  double residual = 0.0;
  for (Eigen::Index row = 0; row < lambda.size(); row += stride) {
    residual = std::max(residual, std::abs(std::min(lambda[row], c[row] / (dt_s * W(row, row)))));
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
// with friction, then the tangent pair moves together by one step against its residual and is
// projected onto the disc of radius μ λ_n (Jean & Moreau's non-smooth contact dynamics, in its
// simplest blocked form):
//   λ_t ← Proj_{|·| ≤ μλ_n}(λ_t − r_t / (Δt ω))   (StepTangentialImpulse).
// One step size for both tangents is what makes the fixed point Coulomb's law: inside the disc
// r_t = 0 (stick); on its rim r_t = −k λ_t with k > 0, friction opposite the sliding velocity.
// (Relaxing the two rows each by its own diagonal, as this solver once did, leaves a fixed point
// with λ_t ∥ −diag(W_tt)⁻¹ r_t, not opposite the slip when W_t1t1 ≠ W_t2t2.) The residual is
// CalcFrictionResidual's, so the tangential part is converged too, not only the normal rows.
ContactSolveReport SolveProjectedGaussSeidel(const Eigen::MatrixXd& W, const Eigen::VectorXd& rhs,
                                             double dt_s, int stride, double mu,
                                             const Eigen::VectorXd* mu_per_contact,
                                             const ContactSolveOptions& options,
                                             Eigen::VectorXd* lambda) {
  ContactSolveReport report;
  const Eigen::Index rows = rhs.size();
  // Wᵀ, so that a row of W is contiguous in memory (W is column-major and, with a rotating
  // tool, not symmetric).
  const Eigen::MatrixXd W_rows = W.transpose();
  for (report.iterations = 1; report.iterations <= options.max_iterations; ++report.iterations) {
    for (Eigen::Index normal = 0; normal < rows; normal += stride) {
      // Residual of the normal row of ΔtWλ = rhs, solved for λ_n with the others fixed.
      const double r_n = dt_s * W_rows.col(normal).dot(*lambda) - rhs[normal];
      (*lambda)[normal] = std::max(0.0, (*lambda)[normal] - r_n / (dt_s * W(normal, normal)));
      if (stride == 3) {
        const double mu_contact = mu_per_contact ? (*mu_per_contact)[normal / 3] : mu;
        const Eigen::Vector2d r_t(dt_s * W_rows.col(normal + 1).dot(*lambda) - rhs[normal + 1],
                                  dt_s * W_rows.col(normal + 2).dot(*lambda) - rhs[normal + 2]);
        lambda->segment<2>(normal + 1) = StepTangentialImpulse(
            lambda->segment<2>(normal + 1), r_t, W.block<2, 2>(normal + 1, normal + 1), dt_s,
            mu_contact * (*lambda)[normal]);
      }
    }
    report.residual = stride == 3 ? CalcFrictionResidual(W, rhs, dt_s, mu, mu_per_contact, *lambda)
                                  : CalcNormalResidual(W, rhs, dt_s, stride, *lambda);
    if (report.residual <= options.tolerance) {
      report.converged = true;
      break;
    }
  }
  report.iterations = std::min(report.iterations, options.max_iterations);
  return report;
}

// LU factor of M restricted to the free rows, in the order they entered. M is not symmetric
// when the tool rotates (the coupling's torque Jacobian enters A_L), but its symmetric part is
// positive definite, so every leading block has one too and LU needs no pivoting. Appending row
// e borders the factor in O(k²), two triangular solves:
//   [M_ff m_c; m_rᵀ M_ee] = [L 0; lᵀ 1] [U u; 0 δ],   L u = m_c,  Uᵀ l = m_r,  δ = M_ee − lᵀu.
// Rows leaving (the rarer event) rebuild it. Against refactoring M_ff by pivoted LU for every
// entering row, this takes block_press's frames (~210 rows, ~70 active) from 1.35 to ~0.3 ms.
class FreeSetFactor {
 public:
  explicit FreeSetFactor(const Eigen::MatrixXd& M) : M_(M), LU_(M.rows(), M.rows()) {}

  // False, leaving the factor as it was, when the row is numerically dependent on the others.
  bool Append(const std::vector<Eigen::Index>& rows_before, Eigen::Index row) {
    const Eigen::Index k = static_cast<Eigen::Index>(rows_before.size());
    Eigen::VectorXd u(k), l(k);
    for (Eigen::Index a = 0; a < k; ++a) {
      u[a] = M_(rows_before[a], row);
      l[a] = M_(row, rows_before[a]);
    }
    LU_.topLeftCorner(k, k).triangularView<Eigen::UnitLower>().solveInPlace(u);
    LU_.topLeftCorner(k, k).triangularView<Eigen::Upper>().transpose().solveInPlace(l);
    const double delta = M_(row, row) - l.dot(u);
    if (!(delta > 0.0)) return false;
    LU_.row(k).head(k) = l.transpose();
    LU_.col(k).head(k) = u;
    LU_(k, k) = delta;
    return true;
  }

  bool Rebuild(const std::vector<Eigen::Index>& rows) {
    std::vector<Eigen::Index> before;
    for (Eigen::Index row : rows) {
      if (!Append(before, row)) return false;
      before.push_back(row);
    }
    return true;
  }

  // z = M_ff⁻¹ rhs_f for the k rows factored.
  Eigen::VectorXd Solve(const Eigen::VectorXd& rhs_f) const {
    const Eigen::Index k = rhs_f.size();
    Eigen::VectorXd z = rhs_f;
    LU_.topLeftCorner(k, k).triangularView<Eigen::UnitLower>().solveInPlace(z);
    LU_.topLeftCorner(k, k).triangularView<Eigen::Upper>().solveInPlace(z);
    return z;
  }

 private:
  const Eigen::MatrixXd& M_;
  Eigen::MatrixXd LU_;  // L below the diagonal (unit diagonal implied), U on and above it
};

// Frictionless unilateral contact as the convex QP  min ½ λᵀ(ΔtW)λ − rhsᵀλ  s.t. λ ≥ 0, whose
// optimality conditions are the LCP. Primal active-set method in the manner of Lawson & Hanson's
// NNLS: add the most violated row to the free set, solve the equality on the free set, and step
// back along the segment (ratio test) when a free λ would turn negative. Finite and exact to
// round-off, unlike Gauss–Seidel, which crawls when many contacts are nearly redundant (a stiff
// body under a flat tool: W is close to the rank-6 tool part). The free-set solves use an
// updated LU factor (FreeSetFactor), with a pivoted LU as the fallback should a row be
// numerically dependent on the others.
ContactSolveReport SolveActiveSet(const Eigen::MatrixXd& W, const Eigen::VectorXd& rhs, double dt_s,
                                  const ContactSolveOptions& options, Eigen::VectorXd* lambda) {
  const Eigen::Index n = rhs.size();
  // A relative 1e-10 on the diagonal keeps the free-set systems non-singular when contacts are
  // redundant (same body point twice, many on a nearly rigid part): without it the solves return
  // garbage there and the method cycles. It changes λ by ~1e-10 relative.
  Eigen::MatrixXd M = dt_s * W;
  M.diagonal().array() += 1e-10 * M.diagonal().cwiseAbs().maxCoeff();
  const double tolerance = options.tolerance * std::max(1.0, rhs.lpNorm<Eigen::Infinity>());
  std::vector<Eigen::Index> free_rows;
  std::vector<bool> is_free(n, false);
  FreeSetFactor factor(M);
  bool factor_holds = true;  // factor is of M over free_rows
  lambda->setZero(n);
  ContactSolveReport report;
  Eigen::VectorXd w = -rhs;  // w = Mλ − rhs
  for (; report.iterations < 3 * n + 10; ++report.iterations) {
    Eigen::Index entering = -1;
    double most_violated = -tolerance;
    for (Eigen::Index i = 0; i < n; ++i)
      if (!is_free[i] && w[i] < most_violated) most_violated = w[i], entering = i;
    if (entering < 0) break;
    factor_holds = factor_holds && factor.Append(free_rows, entering);
    free_rows.push_back(entering);
    is_free[entering] = true;
    while (true) {
      const Eigen::Index k = static_cast<Eigen::Index>(free_rows.size());
      Eigen::VectorXd rhs_f(k);
      for (Eigen::Index a = 0; a < k; ++a) rhs_f[a] = rhs[free_rows[a]];
      Eigen::VectorXd z;
      if (factor_holds) {
        z = factor.Solve(rhs_f);
      } else {
        Eigen::MatrixXd M_ff(k, k);
        for (Eigen::Index a = 0; a < k; ++a)
          for (Eigen::Index b = 0; b < k; ++b) M_ff(a, b) = M(free_rows[a], free_rows[b]);
        z = M_ff.partialPivLu().solve(rhs_f);
      }
      double step = 1.0;
      Eigen::Index limiting = -1;
      for (Eigen::Index a = 0; a < k; ++a) {
        const double current = (*lambda)[free_rows[a]];
        if (z[a] <= 0.0 && current / (current - z[a]) < step) {
          step = current / (current - z[a]);
          limiting = a;
        }
      }
      for (Eigen::Index a = 0; a < k; ++a)
        (*lambda)[free_rows[a]] += step * (z[a] - (*lambda)[free_rows[a]]);
      if (limiting < 0) break;
      // The row that limited the step is exactly at zero by construction; round-off can leave it
      // a hair above, and then it would never leave and the loop would not end.
      (*lambda)[free_rows[limiting]] = 0.0;
      // Rows that reached zero leave the free set.
      std::vector<Eigen::Index> kept;
      for (Eigen::Index row : free_rows) {
        if ((*lambda)[row] > 0.0) {
          kept.push_back(row);
        } else {
          (*lambda)[row] = 0.0;
          is_free[row] = false;
        }
      }
      free_rows.swap(kept);
      factor_holds = free_rows.empty() || factor.Rebuild(free_rows);
      if (free_rows.empty()) break;
    }
    // Only free rows carry λ: O(n k), not O(n²).
    w = -rhs;
    for (Eigen::Index row : free_rows) w += (*lambda)[row] * M.col(row);
  }
  report.residual = CalcNormalResidual(W, rhs, dt_s, 1, *lambda);
  report.converged = report.residual <= std::max(options.tolerance, 1e-9);
  return report;
}

}  // namespace

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
                                        const Eigen::VectorXd* friction_per_contact) {
  if (W.rows() != rhs.size() || W.cols() != rhs.size())
    throw std::invalid_argument("W must be square with one row per constraint row");
  if (friction_per_contact && friction_per_contact->size() * rows_per_contact != rhs.size())
    throw std::invalid_argument("friction_per_contact needs one μ per contact");
  if (lambda->size() != rhs.size()) lambda->setZero(rhs.size());
  if (rhs.size() == 0) return ContactSolveReport{0, 0.0, true};
  switch (options.law) {
    case ContactLaw::kEquality:
      return SolveEquality(W, rhs, dt_s, lambda);
    case ContactLaw::kUnilateral:
      if (rows_per_contact != 1)
        throw std::invalid_argument("unilateral contact uses normal rows only");
      return SolveActiveSet(W, rhs, dt_s, options, lambda);
    case ContactLaw::kFriction:
      if (rows_per_contact != 3) throw std::invalid_argument("friction needs 3 rows per contact");
      return SolveProjectedGaussSeidel(W, rhs, dt_s, 3, options.friction_coefficient,
                                       friction_per_contact, options, lambda);
  }
  throw std::invalid_argument("unknown contact law");
}

}  // namespace hapsim::contact
