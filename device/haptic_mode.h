#pragma once
// What the haptic side renders (DESIGN.md §4–6):
//   kLinear     the paper's linear contact model of the last visual frame, evaluated at 1 kHz
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
  kLinear,
  kLcp,
  kCoupling,
  kReference,
  kPenalty,
  kMaterial,
  kImpact,
  kGodObject
};
// "linear", "lcp", "coupling", "reference", "penalty", "material", "impact", "godobject"
const char* ToString(HapticMode mode);

// penalty, material or impact: a haptic tool whose contact force comes from its own contacts
// at 1 kHz (device/geometric_haptic_contact.h).
inline bool IsGeometricMode(HapticMode mode) {
  return mode == HapticMode::kPenalty || mode == HapticMode::kMaterial ||
         mode == HapticMode::kImpact;
}
// The modes whose 1 kHz force comes from the frame's linear contact model (its rows for lcp; the
// reference builds one every step): the only ones that read the model's body compliance.
inline bool UsesLinearContactModel(HapticMode mode) {
  return mode == HapticMode::kLinear || mode == HapticMode::kLcp ||
         mode == HapticMode::kReference;
}
// The modes that render the frame's world at 1 kHz (each contact model carries it).
inline bool NeedsWorld(HapticMode mode) {
  return IsGeometricMode(mode) || mode == HapticMode::kGodObject;
}

}  // namespace hapsim::device
