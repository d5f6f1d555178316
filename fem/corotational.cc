#include "fem/corotational.h"

#include <algorithm>

#include "fem/polar_decomposition.h"

namespace hapsim::fem {
namespace {

// Deformation gradient F = Σ_i x_i b_iᵀ of tet t.
Eigen::Matrix3d CalcDeformationGradient(const Model& model, const Eigen::VectorXd& x_m, int t) {
  Eigen::Matrix<double, 3, 4> x_local_m;
  for (int a = 0; a < 4; ++a) x_local_m.col(a) = x_m.segment<3>(3 * model.mesh.tets(a, t));
  return x_local_m * model.tet_rest[t].shape_gradients_1_m.transpose();
}

Eigen::Matrix3d CalcRotatedStrain(const Eigen::Matrix3d& F, const Eigen::Matrix3d& R) {
  const Eigen::Matrix3d H = R.transpose() * F - Eigen::Matrix3d::Identity();
  return 0.5 * (H + H.transpose());
}

Eigen::Matrix3d CalcStress(const Eigen::Matrix3d& strain, double mu_Pa, double lambda_Pa) {
  return 2.0 * mu_Pa * strain + lambda_Pa * strain.trace() * Eigen::Matrix3d::Identity();
}

}  // namespace

void CalcElementRotations(const Model& model, const Eigen::VectorXd& x_m, ElasticityKind kind,
                          std::vector<Eigen::Matrix3d>* rotations) {
  rotations->resize(model.num_tets());
  if (kind == ElasticityKind::kLinear) {
    std::fill(rotations->begin(), rotations->end(), Eigen::Matrix3d::Identity());
    return;
  }
  // The deformation gradients first, then their rotations in place, many tets at a time
  // (CalcRotationsOfDeformation: about 3x faster than one at a time).
  for (int t = 0; t < model.num_tets(); ++t)
    (*rotations)[t] = CalcDeformationGradient(model, x_m, t);
  CalcRotationsOfDeformation(rotations->data(), model.num_tets(), rotations->data());
}

namespace {

// A quadratic tet's nodes at positions x (3N) and at rest.
void GatherQuadratic(const Model& model, const Eigen::VectorXd& x_m, int t, P2Nodes* x_local_m,
                     P2Nodes* X_local_m) {
  for (int a = 0; a < kP2Nodes; ++a) {
    const int node = model.mesh.node(a, t);
    x_local_m->col(a) = x_m.segment<3>(3 * node);
    X_local_m->col(a) = model.mesh.rest_positions_m.col(node);
  }
}

// Quadratic tets: f_e = −R K_e (Rᵀ x_e − X_e) (fem/quadratic_tet.h), scattered.
void AddQuadraticElasticForce(const Model& model, const Eigen::VectorXd& x_m,
                              const std::vector<Eigen::Matrix3d>& rotations,
                              Eigen::VectorXd* force_N) {
  P2Nodes x_local_m, X_local_m;
  for (int t = 0; t < model.num_tets(); ++t) {
    GatherQuadratic(model, x_m, t, &x_local_m, &X_local_m);
    const Eigen::Matrix3d& R = rotations[t];
    const P2Nodes u_local_m = R.transpose() * x_local_m - X_local_m;
    const P2Vector f_local_N = MultiplyPackedStiffness(
        model.quadratic_stiffness[t], Eigen::Map<const P2Vector>(u_local_m.data()));
    for (int a = 0; a < kP2Nodes; ++a)
      force_N->segment<3>(3 * model.mesh.node(a, t)) -= R * f_local_N.segment<3>(3 * a);
  }
}

}  // namespace

void CalcElasticForce(const Model& model, const Eigen::VectorXd& x_m,
                      const std::vector<Eigen::Matrix3d>& rotations, Eigen::VectorXd* force_N) {
  force_N->setZero(model.num_dofs());
  if (model.is_quadratic()) {
    AddQuadraticElasticForce(model, x_m, rotations, force_N);
    return;
  }
  for (int t = 0; t < model.num_tets(); ++t) {
    const TetRestData& rest = model.tet_rest[t];
    const Eigen::Matrix3d& R = rotations[t];
    const Eigen::Matrix3d F = CalcDeformationGradient(model, x_m, t);
    const Eigen::Matrix3d sigma_Pa =
        CalcStress(CalcRotatedStrain(F, R), rest.lame_mu_Pa, rest.lame_lambda_Pa);
    // Columns are f_0..f_3 = −V R σ b_i.
    const Eigen::Matrix<double, 3, 4> f_local_N =
        -rest.volume_m3 * (R * sigma_Pa) * rest.shape_gradients_1_m;
    for (int a = 0; a < 4; ++a) force_N->segment<3>(3 * model.mesh.tets(a, t)) += f_local_N.col(a);
  }
}

double CalcElasticEnergy(const Model& model, const Eigen::VectorXd& x_m,
                         const std::vector<Eigen::Matrix3d>& rotations) {
  double energy_J = 0.0;
  if (model.is_quadratic()) {
    P2Nodes x_local_m, X_local_m;
    for (int t = 0; t < model.num_tets(); ++t) {
      GatherQuadratic(model, x_m, t, &x_local_m, &X_local_m);
      const P2Nodes u_local_m = rotations[t].transpose() * x_local_m - X_local_m;
      const Eigen::Map<const P2Vector> u(u_local_m.data());
      energy_J += 0.5 * u.dot(MultiplyPackedStiffness(model.quadratic_stiffness[t], u));
    }
    return energy_J;
  }
  for (int t = 0; t < model.num_tets(); ++t) {
    const TetRestData& rest = model.tet_rest[t];
    const Eigen::Matrix3d strain =
        CalcRotatedStrain(CalcDeformationGradient(model, x_m, t), rotations[t]);
    const double trace = strain.trace();
    energy_J += rest.volume_m3 * (rest.lame_mu_Pa * strain.squaredNorm() +
                                  0.5 * rest.lame_lambda_Pa * trace * trace);
  }
  return energy_J;
}

Eigen::Matrix3d CalcElementStress(const Model& model, const Eigen::VectorXd& x_m,
                                  const Eigen::Matrix3d& rotation, int tet) {
  return CalcStress(CalcRotatedStrain(CalcDeformationGradient(model, x_m, tet), rotation),
                    model.tet_rest[tet].lame_mu_Pa, model.tet_rest[tet].lame_lambda_Pa);
}

}  // namespace hapsim::fem
