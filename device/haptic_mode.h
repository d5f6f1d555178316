#pragma once
// What the haptic side renders (DESIGN.md §4–6):
//   kLinear     the paper's linear contact model of the last visual frame, evaluated at 1 kHz
//   kLcp        the per-contact rows of the last visual frame, the small LCP solved at 1 kHz
//   kCoupling   standard multirate rendering: only the virtual coupling to the visual tool
//   kReference  everything at the haptic step (the ground truth)

namespace hapsim::device {

enum class HapticMode { kLinear, kLcp, kCoupling, kReference };
const char* ToString(HapticMode mode);  // "linear", "lcp", "coupling", "reference"

}  // namespace hapsim::device
