#pragma once
// fem::State: what changes while the body moves. Cheap to copy; a step reads Model, updates State.

#include <Eigen/Core>

#include "fem/model.h"

namespace hapsim::fem {

struct State {
  Eigen::VectorXd x_m;    // (3N) node positions, world frame, m
  Eigen::VectorXd v_m_s;  // (3N) node velocities, world frame, m/s
};

// The body at rest: x = X, v = 0.
inline State MakeRestState(const Model& model) {
  return State{model.rest_positions_m, Eigen::VectorXd::Zero(model.num_dofs())};
}

}  // namespace hapsim::fem
