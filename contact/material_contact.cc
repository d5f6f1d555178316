#include "contact/material_contact.h"

#include <stdexcept>
#include <string>

namespace hapsim::contact {
namespace {

void CheckMaterial(const Material& m, const std::string& whose) {
  auto fail = [&whose](const char* what) {
    throw std::invalid_argument(whose + " material: " + what);
  };
  if (!(m.stiffness >= 0.0 && m.stiffness <= 1.0)) fail("stiffness must be in [0, 1]");
  if (!(m.viscosity >= 0.0 && m.viscosity <= 1.0)) fail("viscosity must be in [0, 1]");
  if (!(m.stickiness_N >= 0.0)) fail("stickiness_N must be >= 0");
  if (!(m.friction_N_m >= 0.0)) fail("friction_N_m must be >= 0");
}

// The tangential part of f (normal n removed); then zero if its size exceeds the stickiness,
// *slipped set.
Eigen::Vector3d CalcStickForce(const Eigen::Vector3d& f, const Eigen::Vector3d& n,
                               double stickiness_N, bool* slipped) {
  const Eigen::Vector3d tangential = f - n.dot(f) * n;
  *slipped = tangential.norm() > stickiness_N;
  return *slipped ? Eigen::Vector3d::Zero() : tangential;
}

}  // namespace

MaterialContact::MaterialContact(const MaterialParams& params, int num_objects)
    : params_(params), pairs_(static_cast<size_t>(num_objects) + 1) {
  if (!(params.max_stiffness_N_m > 0.0))
    throw std::invalid_argument("max_stiffness_N_m must be > 0");
  if (!(params.max_damping_N_s_m >= 0.0))
    throw std::invalid_argument("max_damping_N_s_m must be >= 0");
  if (static_cast<int>(params.objects.size()) > num_objects) {
    throw std::invalid_argument("more object materials than rigid objects");
  }
  CheckMaterial(params.tool, "tool");
  CheckMaterial(params.body, "body");
  CheckMaterial(params.default_object, "object");
  for (const Material& m : params.objects) CheckMaterial(m, "object");
}

const Material& MaterialContact::MaterialOf(int pair) const {
  if (pair == static_cast<int>(pairs_.size()) - 1) return params_.body;
  return pair < static_cast<int>(params_.objects.size()) ? params_.objects[pair]
                                                         : params_.default_object;
}

void MaterialContact::Calc(const std::vector<Contact>& contacts, const Eigen::Isometry3d& X_WT,
                           const Eigen::Vector3d& v_tool_W_m_s,
                           const std::vector<Eigen::Isometry3d>& object_poses,
                           Eigen::Vector3d* F_W_N, Eigen::Vector3d* T_W_N_m) {
  const int body_pair = static_cast<int>(pairs_.size()) - 1;
  for (Pair& pair : pairs_) pair.deepest = nullptr;
  for (const Contact& c : contacts) {
    if (c.gap_m > 0.0) continue;  // touching only: the paper's pairs are colliding ones
    Pair& pair = pairs_[c.rigid_object >= 0 ? c.rigid_object : body_pair];
    if (pair.deepest == nullptr || c.gap_m < pair.deepest->gap_m) pair.deepest = &c;
  }
  const Material& tool = params_.tool;
  F_W_N->setZero();
  T_W_N_m->setZero();
  num_colliding_ = 0;
  num_slips_ = 0;
  for (int j = 0; j < static_cast<int>(pairs_.size()); ++j) {
    Pair& pair = pairs_[j];
    if (pair.deepest == nullptr) {
      pair.was_colliding = false;
      continue;
    }
    const Contact& c = *pair.deepest;
    const Material& object = MaterialOf(j);
    // The object's frame for its stored point: its pose, or the world for the body.
    const Eigen::Isometry3d X_WO = j == body_pair ? Eigen::Isometry3d::Identity() : object_poses[j];
    const Eigen::Vector3d P_C0_T = X_WT.inverse() * c.p_tool_W_m;
    const Eigen::Vector3d P_C1_O = X_WO.inverse() * c.p_body_W_m;
    if (!pair.was_colliding) {  // contact begins: store the witness points
      pair.P_F0_T_m = P_C0_T;
      pair.P_F1_O_m = P_C1_O;
      pair.was_colliding = true;
    }
    const Eigen::Vector3d N_m = c.gap_m * c.n_W;  // depth d along −n: out of the object
    const Eigen::Vector3d Cf = params_.max_stiffness_N_m * tool.stiffness * object.stiffness * N_m;
    const Eigen::Vector3d Vf =
        params_.max_damping_N_s_m * tool.viscosity * object.viscosity * v_tool_W_m_s;
    bool slipped0 = false, slipped1 = false;
    const Eigen::Vector3d Tf0 =
        CalcStickForce(tool.friction_N_m * (X_WT.linear() * (P_C0_T - pair.P_F0_T_m)), c.n_W,
                       tool.stickiness_N, &slipped0);
    const Eigen::Vector3d Tf1 =
        CalcStickForce(object.friction_N_m * (X_WO * pair.P_F1_O_m - c.p_body_W_m), c.n_W,
                       object.stickiness_N, &slipped1);
    if (slipped0) pair.P_F0_T_m = P_C0_T;
    if (slipped1) pair.P_F1_O_m = P_C1_O;
    num_slips_ += (slipped0 ? 1 : 0) + (slipped1 ? 1 : 0);
    const Eigen::Vector3d force = Cf - Vf + Tf0 + Tf1;
    *F_W_N += force;
    *T_W_N_m += (c.p_tool_W_m - X_WT.translation()).cross(force);
    ++num_colliding_;
  }
  if (num_colliding_ > 1) {
    *F_W_N /= num_colliding_;
    *T_W_N_m /= num_colliding_;
  }
}

}  // namespace hapsim::contact
