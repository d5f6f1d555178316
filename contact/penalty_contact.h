#pragma once
// Penalty 6-DOF rendering (paper 000: Gregory, Mascarenhas, Ehmann, Lin and Manocha, "Six
// degree-of-freedom haptic display of polygonal models", IEEE Visualization 2000, §5), on the
// haptic tool's contacts at 1 kHz (contact/haptic_contact_finder.h).
//
// Restoring force (§5.1–5.2): per contact pair (the tool against one rigid object, or against
// the deformable body), with the pair's penetration depth d (the deepest of its contacts, d = −gap)
// and the predictive margin ε,
//   f_pair = k (ε + d)          for d > −ε   (contacts within ε count: the surface "grown" by ε)
// along the contact normals, with ε = v_max Δt, v_max the bound on the speed of any tool point
// (|v| + |ω| R, R the tool's bounding radius) and Δt the haptic step: a contact is felt one step
// before it happens, so the tool is slowed before it penetrates. k = 0.6 N/mm in the paper.
// The pair's force is applied at its contact manifold: shared among its contacts in proportion
// to each one's own depth ε + d_i (so a flat face resting on a plate is pushed at the centroid of
// its corners, with no spurious torque), each along its own normal; the torque is Σ r_i × f_i
// about the tool's centre of mass (§5.1). Summing k over every contact point instead would make
// the stiffness grow with the number of points a mesh happens to have.
//
// Force smoothing (§5.3), per step, with F_p the force of the last step and F_c the new one:
//   |F_c − F_p| > 2 F_max:  F = F_p + F_max (F_c − F_p)/|F_c − F_p|
//   |F_c − F_p| >   F_max:  F = (F_p + F_c)/2
//   otherwise               F = F_c
// so the force changes by at most F_max per step (the paper states it for magnitudes; here for
// the vector). The torque likewise with T_max.

#include <Eigen/Core>
#include <vector>

#include "contact/contact.h"

namespace hapsim::contact {

struct PenaltyParams {
  double stiffness_N_m = 600.0;         // k: 0.6 N/mm (paper 000 §5.1)
  bool predictive_margin = true;        // ε = v_max Δt (§5.2); false: ε = 0
  double max_force_change_N = 0.5;      // F_max per step (§5.3); > 0
  double max_torque_change_N_m = 0.02;  // T_max per step; > 0
};

// The limited change of §5.3 from `previous` towards `current` (vectors of any meaning).
Eigen::Vector3d LimitChange(const Eigen::Vector3d& previous, const Eigen::Vector3d& current,
                            double max_change);

class PenaltyContact {
 public:
  // num_objects: the scene's rigid objects (pairs are those plus the deformable body).
  // Throws std::invalid_argument for k ≤ 0 or a limit ≤ 0.
  PenaltyContact(const PenaltyParams& params, int num_objects);

  // ε for a tool moving at v and ω with bounding radius R over a step of dt_s (0 without the
  // predictive margin).
  double CalcMargin(const Eigen::Vector3d& v_W_m_s, const Eigen::Vector3d& w_W_rad_s,
                    double bounding_radius_m, double dt_s) const;

  // The smoothed force and torque on the tool (world; torque about x_tool_W_m) from contacts
  // found within margin_m (ε). Updates the smoothing's memory. Allocates nothing.
  void Calc(const std::vector<Contact>& contacts, double margin_m,
            const Eigen::Vector3d& x_tool_W_m, Eigen::Vector3d* F_W_N, Eigen::Vector3d* T_W_N_m);

  // The unsmoothed force and torque of the last Calc (the paper's restoring force).
  const Eigen::Vector3d& raw_force_W_N() const { return raw_F_W_N_; }
  const Eigen::Vector3d& raw_torque_W_N_m() const { return raw_T_W_N_m_; }
  const PenaltyParams& params() const { return params_; }

 private:
  PenaltyParams params_;
  std::vector<double> pair_depth_m_;      // per pair (object i at i, the body at the end): max
  std::vector<double> pair_depth_sum_m_;  // per pair: Σ of its contacts' depths
  Eigen::Vector3d F_W_N_ = Eigen::Vector3d::Zero();  // the last smoothed force and torque
  Eigen::Vector3d T_W_N_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d raw_F_W_N_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d raw_T_W_N_m_ = Eigen::Vector3d::Zero();
};

}  // namespace hapsim::contact
