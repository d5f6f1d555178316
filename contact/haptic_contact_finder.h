#pragma once
// The haptic tool's contacts at the haptic rate, for the haptic modes that work on geometry at
// 1 kHz (penalty, material, impact; device/geometric_haptic_contact.h): the tool against the
// world as the last visual frame left it. The rigid objects stand at the poses the frame gave
// them; the deformable body is its surface at the frame's node positions, a rigid snapshot until
// the next frame (the paper 000 and 003 systems render rigid parts only; here a soft body is
// rendered as rigid between frames, and its deformation arrives at the visual rate).
//
// Each contact is measured at the tool's current pose alone (no sweep): the modes that want a
// predictive margin (penalty's ε = v Δt) widen the search with the `margin_m` they pass.
// Contacts are those of the visual frame (contact/collision_detection.h, contact/rigid_objects.h),
// with the same conventions (contact/contact.h): n_W out of the tool, gap = (p_body − p_tool)·n;
// against the body, only its node contacts (and a sphere's centre against its faces): the tool's
// feature points against faces and the edge-versus-edge stage cost O(features × faces): on
// block_press's cylinder the feature stage was 190 µs of a 284 µs step (97 µs without it; 427 µs
// before the tree was refitted once a frame and the margin set per search), and the 1 kHz modes
// push along normals that the node contacts give. The body's tree is refitted once a frame, the
// detection margin set per search (SetMargin), so a step pays for the broad phase and the node
// distances.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "contact/collision_detection.h"
#include "contact/contact.h"
#include "contact/rigid_objects.h"
#include "core/tool_shape.h"
#include "fem/model.h"

namespace hapsim::contact {

class HapticContactFinder {
 public:
  // `body` null: no deformable body. max_margin_m bounds the margins Find may be given (the
  // detectors' own margin; larger asks throw). Throws std::invalid_argument for a bad tool shape
  // or objects (as RigidObjectContacts and CollisionDetector do) or max_margin_m < 0.
  HapticContactFinder(const fem::Model* body, const ToolShape& tool,
                      const std::vector<RigidObject>& objects, double max_margin_m);
  ~HapticContactFinder();

  // The last visual frame's world: body node positions (3N, world, m; ignored without a body)
  // and each rigid object's pose. Called at the visual rate (refits the body's tree).
  void SetBodyPositions(const Eigen::VectorXd& x_m);
  void SetObjectPose(int i, const Eigen::Isometry3d& X_WO) { objects_.SetPose(i, X_WO); }

  // Contacts of the tool at X_WT whose gap is ≤ margin_m (taken into [0, max_margin_m]; NaN as
  // 0): clears and fills *contacts. Allocates only while its buffers grow (reserve them with a
  // warm-up). Does not throw.
  void Find(const Eigen::Isometry3d& X_WT, double margin_m, std::vector<Contact>* contacts);

  int num_objects() const { return objects_.num_objects(); }
  const RigidObject& object(int i) const { return objects_.object(i); }
  double max_margin_m() const { return max_margin_m_; }

 private:
  double max_margin_m_;
  std::unique_ptr<CollisionDetector> detector_;  // with a body
  Eigen::VectorXd x_body_m_;                     // the snapshot's node positions
  RigidObjectContacts objects_;
};

}  // namespace hapsim::contact
