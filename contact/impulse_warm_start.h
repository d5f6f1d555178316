#pragma once
// The frame's contact solve's start from the impulses of the frame before: the friction solve's
// (issue 25 item 2) and the unilateral active-set solve's (item 3).
//
// A press changes the contact impulses slowly from one visual frame to the next, but the frame
// detects its contacts anew, in a new order, with tangents chosen from the new normals. A cold
// start (λ = 0) made SolveFrictionOnWorkingSet find the loaded contacts and their stick/slip
// states again every frame: a median of 34 sweeps a solve on block_press_friction, 17.5 with
// this start (frames.csv's solver_iterations, 2026-11-27). The unilateral active-set solve
// entered its ~70 loaded rows one at a time, each entry an equality solve and a pass over every
// row's slack (block_press, ≥ 200 contacts: 70 iterations a frame); started from the last frame's
// loaded rows, it factors them at once and only corrects the difference.
// This carries a contact's impulse over when the new frame has a contact of the same identity:
// the same body nodes (on an embedded collision surface: the same surface points; weights may
// differ), the same rigid object, the same side (on the tool or not). The normal impulse is kept;
// the tangential one is kept as a world vector and projected onto the new tangent plane (the normal
// may have turned), then written in the new tangents (CalcTangents). Contacts with no body node
// (the tool on a rigid object) have no identity that survives a frame and start at zero, as do
// identities found twice in either frame.
//
// The start only speeds the solve up when the solve converges: the solver clamps it to be
// admissible and stops on the same residual, so it returns the cold start's solution to that
// tolerance (FrameFrictionSolver.WarmStartReachesTheSameSolution). A solve cut off at its sweep
// cap returns an iterate that depends on the start, and so on the frames before.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "contact/contact.h"

namespace hapsim::contact {

class ImpulseWarmStart {
 public:
  // rows_per_contact: 1 (normal rows alone) or 3 (normal, t1, t2).
  explicit ImpulseWarmStart(int rows_per_contact = 3);

  // Keeps the contact forces λ (rows_per_contact rows a contact; N) the frame solved for
  // `contacts`.
  void Record(const std::vector<Contact>& contacts, const Eigen::VectorXd& lambda);

  // λ to start this frame's solve with (rows_per_contact rows a contact), from the recorded frame.
  Eigen::VectorXd Start(const std::vector<Contact>& contacts);

  // Contacts of the last Start that found a recorded impulse.
  int num_carried() const { return num_carried_; }

 private:
  // The contact's surface points (its nodes, or an embedded surface's points), the rigid object
  // and on_tool, each index + 1 packed into two words: (p0, p1) and (p2, object, on_tool), the
  // points' in 32 bits each, the object's in 31 (indices ≥ −1; an object's below 2³¹ − 1). Compared
  // as two integers, the sort and the searches took 0.045 → 0.03 ms of block_press's frames with
  // ~210 contacts, where std::array<int, 5> compared element by element.
  struct Identity {
    std::uint64_t high = 0, low = 0;
    bool operator<(const Identity& other) const {
      return high < other.high || (high == other.high && low < other.low);
    }
    bool operator==(const Identity& other) const { return high == other.high && low == other.low; }
    bool operator!=(const Identity& other) const { return !(*this == other); }
  };
  static bool HasIdentity(const Contact& contact) { return contact.nodes[0] >= 0; }
  static Identity IdentityOf(const Contact& contact);

  struct Force {
    double normal_N = 0.0;
    Eigen::Vector3d tangential_W_N = Eigen::Vector3d::Zero();
    bool ambiguous = false;  // the identity was found twice in the recorded frame
  };
  int rows_per_contact_;
  std::vector<std::pair<Identity, Force>> recorded_;  // sorted by identity
  int num_carried_ = 0;
};

}  // namespace hapsim::contact
