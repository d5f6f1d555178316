#include "fem/probe.h"

#include <Eigen/Dense>

namespace hapsim::fem {

std::optional<ProbeBinding> BindProbe(const Model& model, const Eigen::Vector3d& p_m) {
  constexpr double kInsideTolerance = 1e-9;  // a point on a face or node belongs to a tet
  std::optional<ProbeBinding> best;
  double best_min_weight = -kInsideTolerance;
  for (int t = 0; t < model.num_tets(); ++t) {
    // b_i are the gradients of the barycentric coordinates: w_i(p) = 1/4 + b_i·(p − centroid).
    Eigen::Vector3d centroid_m = Eigen::Vector3d::Zero();
    for (int a = 0; a < 4; ++a)
      centroid_m += 0.25 * model.mesh.rest_positions_m.col(model.mesh.tets(a, t));
    const Eigen::Vector4d weights =
        Eigen::Vector4d::Constant(0.25) +
        model.tet_rest[t].shape_gradients_1_m.transpose() * (p_m - centroid_m);
    if (weights.minCoeff() >= best_min_weight) {
      best_min_weight = weights.minCoeff();
      best = ProbeBinding{t, weights};
    }
  }
  return best;
}

Eigen::Vector3d CalcProbeDisplacement(const Model& model, const State& state,
                                      const ProbeBinding& probe) {
  Eigen::Vector3d u_m = Eigen::Vector3d::Zero();
  if (model.is_quadratic()) {
    // The quadratic tet's shape functions at the probe's barycentric coordinates in its corner
    // tet, which are its reference coordinates ξ = (w_1, w_2, w_3) in a straight tet.
    const Eigen::Matrix<double, kP2Nodes, 1> N = CalcP2ShapeFunctions(probe.barycentric.tail<3>());
    for (int a = 0; a < kP2Nodes; ++a) {
      const int node = model.mesh.node(a, probe.tet);
      u_m += N[a] * (state.x_m.segment<3>(3 * node) - model.rest_positions_m.segment<3>(3 * node));
    }
    return u_m;
  }
  for (int a = 0; a < 4; ++a) {
    const int node = model.mesh.tets(a, probe.tet);
    u_m += probe.barycentric[a] *
           (state.x_m.segment<3>(3 * node) - model.rest_positions_m.segment<3>(3 * node));
  }
  return u_m;
}

}  // namespace hapsim::fem
