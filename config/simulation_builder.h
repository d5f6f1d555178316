#pragma once
// Turns the simulation sections of a scene (tool, coupling, contact, haptic) into the options of
// the visual frame and the multirate simulator: the one mapping `hapsim sim`, the tests and the
// two-process run share.

#include "config/scene.h"
#include "contact/visual_frame.h"
#include "device/multirate_simulator.h"

namespace hapsim::config {

// Gravity, coupling, detection margin and the contact law's response options. The visual and
// haptic steps are left to the caller (MultirateSimulator sets them from MultirateOptions).
contact::VisualFrameOptions MakeVisualFrameOptions(const Scene& scene);

// The haptic side for `mode` at `steps_per_frame` haptic steps per visual frame. `mode` is the
// scene's haptic.mode (checked against the contact law when the scene was loaded) or a
// command-line override: throws InputError naming `mode_option` (e.g. "--mode") if it is lcp and
// the contact law is friction.
device::MultirateOptions MakeMultirateOptions(const Scene& scene, device::HapticMode mode,
                                              int steps_per_frame, const std::string& mode_option);

}  // namespace hapsim::config
