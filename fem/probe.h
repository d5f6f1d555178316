#pragma once
// Probes: material points of the body whose displacement is reported. A probe is bound once, at
// rest, to the tet that contains it and its barycentric weights; it then moves with that tet
// (linear interpolation of the node displacements, exact for the linear-tet field; for quadratic
// tets the quadratic shape functions at the same coordinates, exact for a straight element's).

#include <Eigen/Core>
#include <optional>

#include "fem/model.h"
#include "fem/state.h"

namespace hapsim::fem {

struct ProbeBinding {
  int tet = -1;
  Eigen::Vector4d barycentric = Eigen::Vector4d::Zero();  // weights of the tet's nodes, sum 1
};

// The tet containing rest point p_m (barycentric weights ≥ −tolerance, relative), or nullopt
// if p_m is outside the body. Linear search: done once per probe.
std::optional<ProbeBinding> BindProbe(const Model& model, const Eigen::Vector3d& p_m);

// Displacement u = Σ_i w_i (x_i − X_i) of a bound probe, m.
Eigen::Vector3d CalcProbeDisplacement(const Model& model, const State& state,
                                      const ProbeBinding& probe);

}  // namespace hapsim::fem
