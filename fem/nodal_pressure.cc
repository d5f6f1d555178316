#include "fem/nodal_pressure.h"

#include <stdexcept>

namespace hapsim::fem {

void EnableNodalPressure(Model* model) {
  if (model->is_quadratic())
    throw std::invalid_argument(
        "average nodal pressure is a remedy for linear tets (element p1_nodal_pressure), not "
        "quadratic ones");
  NodalPressure& nodal = model->nodal_pressure;
  nodal.node_volume_m3 = Eigen::VectorXd::Zero(model->num_nodes());
  nodal.node_bulk_Pa = Eigen::VectorXd::Zero(model->num_nodes());
  for (int t = 0; t < model->num_tets(); ++t) {
    const TetRestData& rest = model->tet_rest[t];
    const double bulk_Pa = rest.lame_lambda_Pa + 2.0 / 3.0 * rest.lame_mu_Pa;
    for (int a = 0; a < 4; ++a) {
      const int n = model->mesh.tets(a, t);
      nodal.node_volume_m3[n] += rest.volume_m3 / 4.0;
      nodal.node_bulk_Pa[n] += bulk_Pa * rest.volume_m3 / 4.0;
    }
  }
  for (int n = 0; n < model->num_nodes(); ++n)
    if (nodal.node_volume_m3[n] > 0.0) nodal.node_bulk_Pa[n] /= nodal.node_volume_m3[n];
}

namespace {

// The volumetric strain θ_e = tr(R_eᵀ F_e − I) of tet t.
double CalcVolumetricStrain(const Model& model, const Eigen::VectorXd& x_m,
                            const Eigen::Matrix3d& rotation, int t) {
  const Eigen::Matrix<double, 3, 4>& b = model.tet_rest[t].shape_gradients_1_m;
  double trace = -3.0;
  for (int a = 0; a < 4; ++a)
    trace += (rotation * b.col(a)).dot(x_m.segment<3>(3 * model.mesh.tets(a, t)));
  return trace;
}

// θ_n = Σ_{e∋n} (V_e/4) θ_e / V_n for every node.
void CalcNodalStrains(const Model& model, const Eigen::VectorXd& x_m,
                      const std::vector<Eigen::Matrix3d>& rotations, Eigen::VectorXd* node_strain) {
  const NodalPressure& nodal = model.nodal_pressure;
  node_strain->setZero(model.num_nodes());
  for (int t = 0; t < model.num_tets(); ++t) {
    const double share =
        model.tet_rest[t].volume_m3 / 4.0 * CalcVolumetricStrain(model, x_m, rotations[t], t);
    for (int a = 0; a < 4; ++a) (*node_strain)[model.mesh.tets(a, t)] += share;
  }
  for (int n = 0; n < model.num_nodes(); ++n)
    if (nodal.node_volume_m3[n] > 0.0) (*node_strain)[n] /= nodal.node_volume_m3[n];
}

}  // namespace

void CalcAveragedNodalPressures(const Model& model, const Eigen::VectorXd& x_m,
                                const std::vector<Eigen::Matrix3d>& rotations,
                                Eigen::VectorXd* node_strain,
                                Eigen::VectorXd* element_pressure_Pa) {
  CalcNodalStrains(model, x_m, rotations, node_strain);
  element_pressure_Pa->resize(model.num_tets());
  for (int t = 0; t < model.num_tets(); ++t) {
    double sum_Pa = 0.0;
    for (int a = 0; a < 4; ++a) {
      const int n = model.mesh.tets(a, t);
      sum_Pa += model.nodal_pressure.node_bulk_Pa[n] * (*node_strain)[n];
    }
    (*element_pressure_Pa)[t] = sum_Pa / 4.0;
  }
}

double CalcNodalVolumetricEnergy(const Model& model, const Eigen::VectorXd& x_m,
                                 const std::vector<Eigen::Matrix3d>& rotations) {
  Eigen::VectorXd node_strain;
  CalcNodalStrains(model, x_m, rotations, &node_strain);
  const NodalPressure& nodal = model.nodal_pressure;
  return 0.5 *
         (nodal.node_volume_m3.array() * nodal.node_bulk_Pa.array() * node_strain.array().square())
             .sum();
}

}  // namespace hapsim::fem
