#pragma once
// Grasping tissue (issue 28): a tool that is a grasper (scene key tool.grasp) holds the body's
// surface points that lie inside its jaws when the device's button closes them, and lets them go
// when it opens. A held point is attached where the jaws took it, at p_T in the tool frame, by
// three bilateral rows, one per tool axis e_k (world: R_WT e_k):
//
//   g_k = (x_node − X_WT p_T)·e_k = 0,    J_u = e_kᵀ at the node,  J_v = −e_kᵀ,  J_ω = −(r × e_k)ᵀ
//
// with r = X_WT p_T − x_tool. These are contact rows (contact/contact.h) whose normal is e_k and
// whose gap is the point's offset from its attachment along e_k, with λ of either sign: the
// equality rows of the paper's linear contact model, so the visual frame's response, the linear
// model and the lcp rows carry them unchanged in form and the device feels the tissue's pull
// between frames.
//
// The jaws are a ball in the tool frame (centre, radius): a point is taken if it lies inside at
// the frame the button goes down. A point whose grip force, the norm of its three rows' λ (N),
// exceeds max_force_N after a frame slips out: it is let go from the next frame on (the grip of
// real forceps is limited by friction on the jaws; this is the limit, not its mechanism).
//
// While a point is held, the tool's contacts with the faces and edges around it are dropped
// (DropToolContactsOnHeldPoints): they move with the jaws, and a unilateral row nearly dependent
// on a bilateral one (a face contact on held nodes) gives the 1 kHz solve an unbounded pair of
// impulses, as held near-twin rows did (haptic_lcp_solver.h).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <limits>
#include <vector>

#include "contact/contact.h"

namespace hapsim::contact {

struct GraspOptions {
  Eigen::Vector3d jaw_center_T_m = Eigen::Vector3d::Zero();  // the jaws' ball, tool frame, m
  double jaw_radius_m = 0.0;                                 // > 0
  // Grip force per held point past which it slips, N (> 0; infinity: never).
  double max_force_N = std::numeric_limits<double>::infinity();
};

class TissueGrasp {
 public:
  // `candidate_nodes`: the body's nodes a grasp may take (its free surface nodes). Throws
  // std::invalid_argument on a radius or force limit that is not positive.
  TissueGrasp(const GraspOptions& options, std::vector<int> candidate_nodes, int num_nodes);

  // Takes every candidate node inside the jaws at tool pose X_WT, body positions x_m (3N);
  // returns how many. Closing closed jaws takes nothing new.
  int Close(const Eigen::Isometry3d& X_WT, const Eigen::VectorXd& x_m);
  void Open();  // lets every point go

  const std::vector<int>& held_nodes() const { return held_nodes_; }
  bool Holds(int node) const { return node >= 0 && is_held_[static_cast<size_t>(node)] != 0; }

  // Removes the tool–body contacts (on the tool, no rigid object, not grasp rows) that touch a
  // held node; returns how many.
  int DropToolContactsOnHeldPoints(std::vector<Contact>* contacts) const;
  // Appends the three grasp rows of every held node at tool pose X_WT and body positions x_m.
  void AddContacts(const Eigen::Isometry3d& X_WT, const Eigen::VectorXd& x_m,
                   std::vector<Contact>* contacts) const;
  // After the frame's solve: a held node whose grip force ‖(λ_1, λ_2, λ_3)‖ (its three grasp
  // rows among `contacts`, λ one entry per contact, N) exceeds the limit is let go. Returns how
  // many slipped.
  int LetSlip(const std::vector<Contact>& contacts, const Eigen::VectorXd& lambda_N);
  // The frame's sanity pass for held points: each is put back where the jaws hold it, X_WT p_T,
  // moving with the jaws (v + ω × r), as the pass moves a node out of the tool. The rows hold
  // the point's velocity relative to the jaws at a target (−β φ/Δt) through a compliance W that
  // is not the body's own (warped, or from the lagged factor): what is left over in that
  // velocity, ∝ (W_true − W) λ, would add up over frames to an offset (1.7 mm at a 0.3 N pull on
  // scenes/retraction.yaml with the exact compliance) and, warped, to a drift that ran away
  // (2.5 → 15 mm over four frames: W's 10 % error swamps the stiff relative modes of points
  // 5 mm apart). Returns the largest distance a point was moved, m.
  double MoveHeldPointsToTheJaws(const Eigen::Isometry3d& X_WT, const Eigen::Vector3d& v_W_m_s,
                                 const Eigen::Vector3d& w_W_rad_s, Eigen::VectorXd* x_m,
                                 Eigen::VectorXd* v_m_s) const;

 private:
  void Release(int node);

  GraspOptions options_;
  std::vector<int> candidate_nodes_;
  std::vector<std::uint8_t> is_held_;      // per body node
  std::vector<int> held_nodes_;            // in the order taken
  std::vector<Eigen::Vector3d> held_T_m_;  // each held node's attachment point, tool frame
  bool closed_ = false;
};

}  // namespace hapsim::contact
