#pragma once
// The largest natural angular frequency of a body at rest, ω_max = sqrt(λ_max(M⁻¹ K)), with the
// lumped mass M and the rest stiffness K over the free dofs. Symplectic (explicit) Euler without
// damping is stable for Δt < 2 / ω_max (the central-difference limit; e.g. Hughes, The Finite
// Element Method, §9.1); the stability map of scripts/bench.sh draws that line. With Rayleigh
// damping applied explicitly the limit is lower: CalcExplicitStableStep.

#include "fem/model.h"

namespace hapsim::fem {

struct MaxFrequencyEstimate {
  double omega_max_rad_s = 0.0;
  int iterations = 0;
  double relative_change = 0.0;  // of the Rayleigh quotient over the last iteration
};

// Power iteration on the symmetric M^(−1/2) K M^(−1/2), from a fixed alternating start (the
// highest mode of a lattice alternates in sign from node to node), until the Rayleigh quotient
// changes by less than `tolerance` relative or after `max_iterations`. The quotient is a lower
// bound of λ_max that converges from below. Throws std::invalid_argument if every dof is fixed.
MaxFrequencyEstimate EstimateMaxFrequency(const Model& model, double tolerance = 1e-6,
                                          int max_iterations = 5000);

// The largest stable step of hapsim's explicit Euler (v⁺ = v + Δt M⁻¹(f − αM v − βK v), then
// x⁺ = x + Δt v⁺) at the top mode ω = omega_max_rad_s, with Rayleigh damping α (1/s), β (s).
// Per mode, with c = α + βω², the step's matrix has trace 2 − (Δt ω)² − Δt c and determinant
// 1 − Δt c; its roots stay in the unit disc (Jury) while (Δt ω)² + 2 Δt c ≤ 4, whose left side
// grows with ω, so the top mode binds:
//   Δt_max = (2/ω) (sqrt(1 + ξ²) − ξ),   ξ = c / (2ω) = α/(2ω) + βω/2,
// which is 2/ω without damping and about 1/(ξω) when ξ ≫ 1 (β alone: 2/(βω²)).
double CalcExplicitStableStep(double omega_max_rad_s, double rayleigh_alpha_1_s,
                              double rayleigh_beta_s);

}  // namespace hapsim::fem
