#pragma once
// Isotropic linear-elastic material with Rayleigh damping, in SI units.

namespace hapsim::fem {

struct Material {
  double youngs_modulus_Pa = 50e3;  // E > 0
  double poisson_ratio = 0.45;      // ν in (-1, 0.5)
  double density_kg_m3 = 1000.0;    // ρ > 0
  double rayleigh_alpha_1_s = 0.0;  // α ≥ 0: mass-proportional damping, D = αM + βK
  double rayleigh_beta_s = 0.0;     // β ≥ 0: stiffness-proportional damping

  // Lamé parameters: μ = E / (2(1+ν)), λ = Eν / ((1+ν)(1−2ν)).
  double lame_mu_Pa() const { return youngs_modulus_Pa / (2.0 * (1.0 + poisson_ratio)); }
  double lame_lambda_Pa() const {
    return youngs_modulus_Pa * poisson_ratio /
           ((1.0 + poisson_ratio) * (1.0 - 2.0 * poisson_ratio));
  }
};

}  // namespace hapsim::fem
