#pragma once
// The contact force of the haptic modes that work on geometry at 1 kHz (device/haptic_mode.h):
// penalty (paper 000), material (paper 003) and impact (paper 001). Each haptic step finds the
// haptic tool's contacts against the world of the last visual frame (HapticContactFinder) and
// turns them into a force and torque on the haptic tool, which HapticStep then integrates with
// the coupling to the device, as it does with the linear model's force in the paper's mode.
//   penalty   k (ε + d) per contact pair, ε = v Δt, smoothed (contact/penalty_contact.h)
//   material  Hooke + viscous + stick–slip, averaged over pairs (contact/material_contact.h)
//   impact    constraint impulses with restitution e (contact/impact_contact.h)

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "contact/haptic_contact_finder.h"
#include "contact/impact_contact.h"
#include "contact/material_contact.h"
#include "contact/penalty_contact.h"
#include "core/rigid_tool.h"
#include "core/tool_integrator.h"
#include "device/haptic_mode.h"

namespace hapsim::device {

struct GeometricContactParams {
  contact::PenaltyParams penalty;
  contact::MaterialParams material;
  contact::ImpactParams impact;
  // Contacts are searched up to this gap: ≥ the largest predictive margin wanted (penalty's
  // ε = v Δt: 2 mm holds a tool point at 2 m/s at 1 kHz) and impact's |s| Δt. m.
  double search_margin_m = 2e-3;
  int max_contacts = 512;  // the contact buffer is reserved for this many (no growth below)
};

class GeometricHapticContact {
 public:
  // mode: kPenalty, kMaterial or kImpact (else std::invalid_argument). `body` (null: none) must
  // outlive this; objects are the scene's rigid objects at their start poses.
  GeometricHapticContact(HapticMode mode, const GeometricContactParams& params,
                         const ToolModel& tool, const fem::Model* body,
                         const std::vector<contact::RigidObject>& objects);

  // The world of the last visual frame: body node positions (3N) and object poses.
  void SetWorld(const Eigen::VectorXd& x_body_m, const std::vector<Eigen::Isometry3d>& X_WO);

  // Contact force and torque on the tool (world; about its centre of mass) for the step whose
  // free system is `system`, at `state`. Allocates nothing once its buffers have grown (a
  // warm-up step with the most contacts reserves them).
  void Calc(const ToolStepSystem& system, const ToolState& state, Eigen::Vector3d* F_W_N,
            Eigen::Vector3d* T_W_N_m);

  int num_contacts() const { return static_cast<int>(contacts_.size()); }
  const std::vector<contact::Contact>& contacts() const { return contacts_; }
  HapticMode mode() const { return mode_; }
  const contact::PenaltyContact& penalty() const { return penalty_; }
  const contact::ImpactContact& impact() const { return impact_; }
  const contact::MaterialContact& material() const { return material_; }

 private:
  HapticMode mode_;
  ToolModel tool_;
  double search_margin_m_;
  double bounding_radius_m_;
  contact::HapticContactFinder finder_;
  contact::PenaltyContact penalty_;
  contact::MaterialContact material_;
  contact::ImpactContact impact_;
  std::vector<Eigen::Isometry3d> object_poses_;
  std::vector<contact::Contact> contacts_;
};

}  // namespace hapsim::device
