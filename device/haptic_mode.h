#pragma once
// What the haptic side renders (DESIGN.md §4–6):
//   kHybrid     the default (issue 25): the frame's active contacts held as the paper's linear
//               model holds them (equalities), and the frame's other candidate rows switched on
//               unilaterally at 1 kHz, so that a fast tool meets a row between frames
//               (HapticLcpSolver with hold_frame_contacts)
//   kLinear     the paper's linear contact model of the last visual frame, evaluated at 1 kHz
//               (its active set frozen: from ~0.25 m/s a tool sinks through, docs/RESULTS.md)
//   kLcp        the per-contact rows of the last visual frame, the small LCP solved at 1 kHz
//   kCoupling   standard multirate rendering: only the virtual coupling to the visual tool
//   kReference  everything at the haptic step (the ground truth)
// The source papers' other systems, as baselines (device/geometric_haptic_contact.h):
//   kPenalty    paper 000: penalty forces k (ε + d) on the haptic tool at 1 kHz, smoothed
//   kMaterial   paper 003: per-object Hooke, viscous and stick–slip forces, averaged over pairs
//   kImpact     paper 001: constraint impulses with a coefficient of restitution at 1 kHz
//   kGodObject  paper 004: a point tool's proxy held on the surfaces' triangles
//   (contact/god_object.h)
// Each works on the world of the last visual frame (rigid objects, the body's surface as rigid).

namespace hapsim::device {

enum class HapticMode {
  kHybrid,
  kLinear,
  kLcp,
  kCoupling,
  kReference,
  kPenalty,
  kMaterial,
  kImpact,
  kGodObject
};
// "hybrid", "linear", "lcp", "coupling", "reference", "penalty", "material", "impact",
// "godobject"
const char* ToString(HapticMode mode);

// What haptic.mode is when a scene does not say (and what --mode defaults to).
constexpr HapticMode kDefaultHapticMode = HapticMode::kHybrid;

// The modes whose 1 kHz step solves on the frame's contact rows (HapticLcpSolver).
inline bool UsesContactRows(HapticMode mode) {
  return mode == HapticMode::kLcp || mode == HapticMode::kHybrid;
}
// Of those, the one that holds the frame's active rows as equalities.
inline bool HoldsFrameContacts(HapticMode mode) { return mode == HapticMode::kHybrid; }

// penalty, material or impact: a haptic tool whose contact force comes from its own contacts
// at 1 kHz (device/geometric_haptic_contact.h).
inline bool IsGeometricMode(HapticMode mode) {
  return mode == HapticMode::kPenalty || mode == HapticMode::kMaterial ||
         mode == HapticMode::kImpact;
}
// The modes whose 1 kHz force comes from the frame's linear contact model (its rows for lcp; the
// reference builds one every step): the only ones that read the model's body compliance.
inline bool UsesLinearContactModel(HapticMode mode) {
  return mode == HapticMode::kLinear || UsesContactRows(mode) || mode == HapticMode::kReference;
}
// The modes that render the frame's world at 1 kHz (each contact model carries it).
inline bool NeedsWorld(HapticMode mode) {
  return IsGeometricMode(mode) || mode == HapticMode::kGodObject;
}

}  // namespace hapsim::device
