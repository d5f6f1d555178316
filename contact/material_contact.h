#pragma once
// Material contact (paper 003: Luciano, Banerjee, DeFanti and Mehrotra, "Realistic cross-platform
// haptic applications using freely-available libraries", §9, after Ruspini et al.'s materials):
// each object has a material of four parameters, and every colliding pair (the tool against one
// rigid object, or against the deformable body) gives a force from the two materials, on the
// haptic tool's contacts at 1 kHz (contact/haptic_contact_finder.h).
//
// For a pair j with penetration vector N_j (its deepest contact: depth d = −gap along −n, pushing
// the tool out), tool velocity v and the pair's stored contact points (below):
//   Hooke       Cf = k_max S_0 S_1 N_j              (k_max the device's largest stiffness)
//   viscous     Vf = b_max V_0 V_1 v                (only while colliding)
//   friction    Tf_0 = F_0 (P_C0 − P_F0),  Tf_1 = F_1 (P_F1 − P_C1)  (tangential parts)
//   Force_j = Cf − Vf + Tf_0 + Tf_1,   Final = (1/J) Σ_j Force_j   (averaged over the J pairs)
// Index 0 is the tool's material, 1 the object's. Stick–slip: when a pair starts colliding, its
// witness points are stored, on the tool in the tool frame (P_F0) and on the object in the
// object's frame (P_F1; the body's in the world, its snapshot standing still between frames).
// While it collides, Tf_i pulls the current witness points P_Ci back to the stored ones; when
// |Tf_i| exceeds the stickiness T_i, the stored point is moved to the current one (a slip) and
// Tf_i is dropped for that step. Tf_0 and Tf_1 are taken in the world, their normal parts removed
// (the paper's "tangential forces"). The paper renders forces only (a 3-DOF PHANToM); here the
// torque of each pair's force about the tool's centre of mass, at its deepest contact's tool point,
// is averaged alike. Averaging is the paper's choice for smoothness: two identical pairs give
// the force of one, so pressing into two touching parts feels like pressing into one.
//
// S and V are fractions (0..1] of the device's k_max and b_max, as the paper's S against GHOST's
// MaxStiffness; F is a tangential stiffness (N/m) and T a force (N).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "contact/contact.h"

namespace hapsim::contact {

struct Material {
  double stiffness = 1.0;     // S in [0, 1]: fraction of k_max
  double viscosity = 0.0;     // V in [0, 1]: fraction of b_max
  double stickiness_N = 0.0;  // T ≥ 0: the tangential force at which a stored point slips
  double friction_N_m = 0.0;  // F ≥ 0: tangential stiffness towards the stored point
};

struct MaterialParams {
  double max_stiffness_N_m = 600.0;  // k_max > 0
  double max_damping_N_s_m = 2.0;    // b_max ≥ 0
  Material tool;
  Material body;                  // the deformable body's
  std::vector<Material> objects;  // per rigid object; missing ones take `default_object`
  Material default_object;
};

class MaterialContact {
 public:
  // num_objects: the scene's rigid objects. Throws std::invalid_argument for a parameter out of
  // its range (naming it) or more object materials than objects.
  MaterialContact(const MaterialParams& params, int num_objects);

  // The averaged force and torque on the tool (world; torque about its centre of mass) from
  // contacts that touch (gap ≤ 0). object_poses: each rigid object's X_WO now (its stored
  // contact point is kept in its frame). Updates the stored points. Allocates nothing.
  void Calc(const std::vector<Contact>& contacts, const Eigen::Isometry3d& X_WT,
            const Eigen::Vector3d& v_tool_W_m_s, const std::vector<Eigen::Isometry3d>& object_poses,
            Eigen::Vector3d* F_W_N, Eigen::Vector3d* T_W_N_m);

  int num_colliding_pairs() const { return num_colliding_; }
  int num_slips() const { return num_slips_; }  // slips at the last Calc
  const MaterialParams& params() const { return params_; }

 private:
  struct Pair {
    const Contact* deepest = nullptr;  // this step's deepest contact (gap ≤ 0), or none
    bool was_colliding = false;
    Eigen::Vector3d P_F0_T_m = Eigen::Vector3d::Zero();  // stored point on the tool, T
    Eigen::Vector3d P_F1_O_m = Eigen::Vector3d::Zero();  // stored point on the object, O (W)
  };
  const Material& MaterialOf(int pair) const;

  MaterialParams params_;
  std::vector<Pair> pairs_;  // object i at i, the body at the end
  int num_colliding_ = 0;
  int num_slips_ = 0;
};

}  // namespace hapsim::contact
