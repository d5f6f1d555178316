#include "contact/haptic_friction_solver.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "contact/contact_solver.h"

namespace hapsim::contact {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

}  // namespace

// All scratch, sized once for max_rows. n rows, m = n/3 contacts; λ and the sums kept with it.
// The rows themselves (n, W, U, body_rhs, mu) are the ContactRowCache it extends.
struct HapticFrictionSolver::Workspace : ContactRowCache {
  Workspace(int max_rows_in, int max_sweeps_in)
      : ContactRowCache(max_rows_in),
        max_rows(max_rows_in),
        max_sweeps(max_sweeps_in),
        rhs(max_rows_in),
        lambda(max_rows_in),
        y(max_rows_in),
        W_diagonal(max_rows_in / 3 + 1),
        W_diagonal_step(max_rows_in / 3 + 1, 0) {}

  void StartFrom(const Eigen::VectorXd& lambda_start);
  // Contact i's 3 × 3 block of W = W_body + U S Uᵀ (rows 3i..3i+2) for this step's S, formed the
  // first time the step needs it: the sweeps and the residual read only the blocks of contacts
  // that carry load or are about to, so that the many that stay separated (the frame's far
  // candidates) cost only their normal velocity. Null if the normal has no compliance (no
  // Gauss–Seidel step exists for it).
  const Eigen::Matrix3d* DiagonalBlock(int i) {
    if (W_diagonal_step[i] != step) {
      const auto U_i = U.middleRows<3>(3 * i);
      W_diagonal[i] = W.block<3, 3>(3 * i, 3 * i) + U_i * S * U_i.transpose();
      W_diagonal_step[i] = step;
    }
    return W_diagonal[i](0, 0) > 0.0 ? &W_diagonal[i] : nullptr;
  }
  // c_i = Δt (y_i + U_i S g) − rhs_i, from the kept sums (h = S g); and its normal row alone.
  Eigen::Vector3d CalcVelocity(int i, const Vector6d& h, double dt_s) const {
    return dt_s * (y.segment<3>(3 * i) + U.middleRows<3>(3 * i) * h) - rhs.segment<3>(3 * i);
  }
  double CalcNormalVelocity(int i, const Vector6d& h, double dt_s) const {
    return dt_s * (y[3 * i] + U.row(3 * i).dot(h)) - rhs[3 * i];
  }
  double Sweep(double dt_s);
  double CalcResidual(double dt_s);

  const int max_rows;
  const int max_sweeps;
  Matrix6d S = Matrix6d::Zero();               // this step's tool compliance
  Eigen::VectorXd rhs;                         // this step's body_rhs − U s_free
  Eigen::VectorXd lambda, y;                   // λ and W_body λ
  std::vector<Eigen::Matrix3d> W_diagonal;     // per contact, this step's (DiagonalBlock)
  std::vector<std::uint64_t> W_diagonal_step;  // the step each was formed at
  std::uint64_t step = 0;                      // Solve's count, from 1
  bool singular_normal = false;                // a needed block had no normal compliance
  Vector6d g = Vector6d::Zero();               // Uᵀλ
};

// λ, y = W_body λ and g = Uᵀλ from a start (zero-sized: λ = 0). Its normal impulses are clamped
// at zero and tangential ones into the disc, so that every iterate is admissible.
void HapticFrictionSolver::Workspace::StartFrom(const Eigen::VectorXd& lambda_start) {
  if (lambda_start.size() == n) {
    lambda.head(n) = lambda_start;
    for (int i = 0; i < n / 3; ++i) {
      lambda[3 * i] = std::max(0.0, lambda[3 * i]);
      lambda.segment<2>(3 * i + 1) =
          ProjectOntoDisc(lambda.segment<2>(3 * i + 1), mu[i] * lambda[3 * i]);
    }
  } else {
    lambda.head(n).setZero();
  }
  MultiplyBody(lambda.head(n), y.head(n));
  g.noalias() = U.topRows(n).transpose() * lambda.head(n);
}

// One Gauss–Seidel sweep over the contacts (SolveContactImpulses' kFriction sweep, with W
// applied through y and g). Returns the largest change of an impulse.
double HapticFrictionSolver::Workspace::Sweep(double dt_s) {
  double largest_change = 0.0;
  Vector6d h = S * g;
  for (int i = 0; i < n / 3; ++i) {
    const int a = 3 * i;
    const Eigen::Vector3d old = lambda.segment<3>(a);
    // Separated and staying so (λ_t is 0 too): the normal velocity alone decides.
    if (old[0] == 0.0 && CalcNormalVelocity(i, h, dt_s) >= 0.0) continue;
    const Eigen::Matrix3d* W_ii = DiagonalBlock(i);
    if (W_ii == nullptr) {
      singular_normal = true;
      return std::numeric_limits<double>::quiet_NaN();
    }
    Eigen::Vector3d c = CalcVelocity(i, h, dt_s);
    Eigen::Vector3d next;
    next[0] = std::max(0.0, old[0] - c[0] / (dt_s * (*W_ii)(0, 0)));
    // The tangential rows see the normal row's new impulse, as in the dense sweep.
    c.tail<2>() += dt_s * W_ii->block<2, 1>(1, 0) * (next[0] - old[0]);
    next.tail<2>() = StepTangentialImpulse(old.tail<2>(), c.tail<2>(), W_ii->block<2, 2>(1, 1),
                                           dt_s, mu[i] * next[0]);
    const Eigen::Vector3d delta = next - old;
    if (delta.isZero(0.0)) continue;
    const double change = delta.cwiseAbs().maxCoeff();
    if (!(change <= largest_change)) largest_change = change;  // NaN propagates
    lambda.segment<3>(a) = next;
    AddContactColumns(a, delta, y.head(n));
    const Vector6d dg = U.middleRows<3>(a).transpose() * delta;
    g += dg;
    h.noalias() += S * dg;
  }
  return largest_change;
}

// CalcFrictionResidual's measure (contact_solver.h) from the kept sums. A separated contact
// whose normal velocity is ≥ 0 meets the law exactly (λ = 0, and a disc of radius 0 moves
// nothing): it adds nothing, and its block is not formed.
double HapticFrictionSolver::Workspace::CalcResidual(double dt_s) {
  const Vector6d h = S * g;
  double residual = 0.0;
  for (int i = 0; i < n / 3; ++i) {
    const int a = 3 * i;
    if (lambda[a] == 0.0 && CalcNormalVelocity(i, h, dt_s) >= 0.0) continue;
    const Eigen::Matrix3d* W_ii = DiagonalBlock(i);
    if (W_ii == nullptr) {  // a contact no sweep reached (cut off by max_sweeps) now approaches
      singular_normal = true;
      return std::numeric_limits<double>::infinity();
    }
    const Eigen::Vector3d c = CalcVelocity(i, h, dt_s);
    const Eigen::Vector2d lambda_t = lambda.segment<2>(a + 1);
    const Eigen::Vector2d moved = StepTangentialImpulse(
        lambda_t, c.tail<2>(), W_ii->block<2, 2>(1, 1), dt_s, mu[i] * lambda[a]);
    residual = std::max({residual, std::abs(std::min(lambda[a], c[0] / (dt_s * (*W_ii)(0, 0)))),
                         (moved - lambda_t).norm()});
  }
  const double scale = lambda.head(n).lpNorm<Eigen::Infinity>();
  return scale > 0.0 ? residual / scale : residual;
}

HapticFrictionSolver::HapticFrictionSolver(int max_rows, int max_sweeps) {
  if (max_rows < 0) throw std::invalid_argument("HapticFrictionSolver: max_rows must be ≥ 0");
  if (max_sweeps < 1) throw std::invalid_argument("HapticFrictionSolver: max_sweeps must be ≥ 1");
  ws_ = std::make_unique<Workspace>(max_rows, max_sweeps);
}

HapticFrictionSolver::~HapticFrictionSolver() = default;
HapticFrictionSolver::HapticFrictionSolver(HapticFrictionSolver&&) noexcept = default;
HapticFrictionSolver& HapticFrictionSolver::operator=(HapticFrictionSolver&&) noexcept = default;

int HapticFrictionSolver::max_rows() const { return ws_->max_rows; }
int HapticFrictionSolver::max_sweeps() const { return ws_->max_sweeps; }

Eigen::Ref<const Eigen::VectorXd> HapticFrictionSolver::last_impulses() const {
  return ws_->lambda.head(std::max(ws_->n, 0));
}

bool HapticFrictionSolver::Prepare(const ContactRows& rows) {
  Workspace& ws = *ws_;
  if (rows.num_rows() > ws.max_rows || rows.rows_per_contact != 3 || !HasConsistentShape(rows) ||
      !ws.Take(rows))
    return false;
  ws.StartFrom(rows.lambda_frame_N);
  return true;
}

bool HapticFrictionSolver::Solve(const ContactRows& rows, const ToolStepSystem& tool,
                                 const Eigen::Vector3d& F_hat_N, const Eigen::Vector3d& T_hat_N_m,
                                 Eigen::Vector3d* F_c_N, Eigen::Vector3d* T_c_N_m) {
  Workspace& ws = *ws_;
  F_c_N->setZero();
  T_c_N_m->setZero();
  last_iterations_ = 0;
  last_residual_ = 0.0;
  last_num_active_ = 0;
  last_num_sliding_ = 0;
  const int n = rows.num_rows();
  if (n > ws.max_rows || rows.rows_per_contact != 3 || !HasConsistentShape(rows) ||
      !(tool.dt_s > 0.0))
    return false;
  const double dt_s = tool.dt_s;
  Vector6d s_free;
  if (!CalcToolCompliance(tool, F_hat_N, T_hat_N_m, &ws.S, &s_free)) return false;
  if (!ws.Holds(rows)) {
    if (!ws.Take(rows)) return false;
    ws.StartFrom(rows.lambda_frame_N);
  }
  if (n == 0) return true;
  ++ws.step;  // the diagonal blocks of S's previous step are stale
  ws.singular_normal = false;
  ws.rhs.head(n) = ws.body_rhs.head(n);
  ws.rhs.head(n).noalias() -= ws.U.topRows(n) * s_free;
  while (last_iterations_ < ws.max_sweeps) {
    ++last_iterations_;
    const double change = ws.Sweep(dt_s);
    if (!std::isfinite(change)) break;  // reported as a failure below
    if (change <= kTolerance * ws.lambda.head(n).lpNorm<Eigen::Infinity>()) break;
  }
  if (!ws.singular_normal) last_residual_ = ws.CalcResidual(dt_s);
  if (ws.singular_normal || !ws.lambda.head(n).allFinite()) {
    ws.n = -1;  // start afresh next time
    last_residual_ = 0.0;
    return false;
  }
  for (int i = 0; i < n / 3; ++i) {
    const double normal = ws.lambda[3 * i];
    if (normal <= 0.0) continue;
    ++last_num_active_;
    if (ws.lambda.segment<2>(3 * i + 1).norm() >= (1.0 - 1e-12) * ws.mu[i] * normal &&
        ws.mu[i] > 0.0)
      ++last_num_sliding_;
  }
  *F_c_N = ws.U.topLeftCorner(n, 3).transpose() * ws.lambda.head(n);
  *T_c_N_m = ws.U.topRightCorner(n, 3).transpose() * ws.lambda.head(n);
  return true;
}

}  // namespace hapsim::contact
