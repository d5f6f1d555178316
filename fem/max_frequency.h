#pragma once
// The largest natural angular frequency of a body at rest, ω_max = sqrt(λ_max(M⁻¹ K)), with the
// lumped mass M and the rest stiffness K over the free dofs. Symplectic (explicit) Euler without
// damping is stable for Δt < 2 / ω_max (the central-difference limit; e.g. Hughes, The Finite
// Element Method, §9.1); the stability map of scripts/bench.sh draws that line.

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

}  // namespace hapsim::fem
