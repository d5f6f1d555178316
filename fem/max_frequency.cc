#include "fem/max_frequency.h"

#include <Eigen/SparseCore>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "fem/stiffness_assembly.h"

namespace hapsim::fem {

MaxFrequencyEstimate EstimateMaxFrequency(const Model& model, double tolerance,
                                          int max_iterations) {
  const int n = model.num_dofs();
  const StiffnessAssembler assembler(model);
  Eigen::SparseMatrix<double> K = assembler.MakeMatrix();
  assembler.Assemble(model,
                     std::vector<Eigen::Matrix3d>(model.num_tets(), Eigen::Matrix3d::Identity()),
                     /*scale=*/1.0, &K);
  // x ↦ M^(−1/2) K M^(−1/2) x on the free dofs (fixed dofs held at zero).
  Eigen::VectorXd inv_sqrt_mass(n);
  bool any_free = false;
  for (int i = 0; i < n; ++i) {
    inv_sqrt_mass[i] = model.dof_is_fixed[i] ? 0.0 : 1.0 / std::sqrt(model.dof_mass_kg[i]);
    any_free = any_free || !model.dof_is_fixed[i];
  }
  if (!any_free) throw std::invalid_argument("every degree of freedom is fixed: nothing vibrates");
  Eigen::VectorXd x(n);
  for (int i = 0; i < n; ++i)
    x[i] = ((i / 3 + i % 3) % 2 == 0 ? 1.0 : -1.0) * (1.0 + 1e-3 * (i % 7));
  x = x.cwiseProduct(inv_sqrt_mass.cwiseSign());  // zero on fixed dofs
  x.normalize();
  MaxFrequencyEstimate estimate;
  double lambda = 0.0;
  for (estimate.iterations = 1; estimate.iterations <= max_iterations; ++estimate.iterations) {
    const Eigen::VectorXd y = inv_sqrt_mass.cwiseProduct(K.selfadjointView<Eigen::Lower>() *
                                                         inv_sqrt_mass.cwiseProduct(x));  // A x
    const double next = x.dot(y);  // Rayleigh quotient, |x| = 1
    estimate.relative_change = std::abs(next - lambda) / std::abs(next);
    lambda = next;
    x = y.normalized();
    if (estimate.relative_change < tolerance) break;
  }
  estimate.iterations = std::min(estimate.iterations, max_iterations);
  estimate.omega_max_rad_s = std::sqrt(std::max(lambda, 0.0));
  return estimate;
}

double CalcExplicitStableStep(double omega_max_rad_s, double rayleigh_alpha_1_s,
                              double rayleigh_beta_s) {
  const double omega = omega_max_rad_s;
  const double xi = rayleigh_alpha_1_s / (2.0 * omega) + 0.5 * rayleigh_beta_s * omega;
  // sqrt(1 + ξ²) − ξ written as 1 / (sqrt(1 + ξ²) + ξ): no cancellation when ξ is large.
  return 2.0 / (omega * (std::sqrt(1.0 + xi * xi) + xi));
}

}  // namespace hapsim::fem
