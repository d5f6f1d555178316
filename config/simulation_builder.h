#pragma once
// Turns the simulation sections of a scene (tool, coupling, contact, haptic) into the options of
// the visual frame and the multirate simulator: the one mapping `hapsim sim`, the tests and the
// two-process run share.

#include <optional>

#include "config/body_builder.h"
#include "config/scene.h"
#include "contact/visual_frame.h"
#include "device/multirate_simulator.h"

namespace hapsim::config {

// Gravity, coupling, detection margin, the contact law's response options and the rigid
// objects. The visual and
// haptic steps are left to the caller (MultirateSimulator sets them from MultirateOptions).
contact::VisualFrameOptions MakeVisualFrameOptions(const Scene& scene);

// The visual frame of the scene: on its deformable body when it has one (built by
// MakeSceneBody, which must outlive the frame), or on its rigid objects alone.
contact::VisualFrame MakeVisualFrame(const Scene& scene, const std::optional<Body>& body,
                                     const contact::VisualFrameOptions& options);

// The haptic mode of a run: the scene's haptic.mode, or `option_value` when given (a
// command-line override). Throws InputError naming `option` (or haptic.mode, when the scene's
// mode is the problem) for an unknown mode, for godobject without a point tool, and for the
// reference mode unless allow_reference (the reference exists in the in-process simulator only).
device::HapticMode ResolveHapticMode(const Scene& scene, const std::string& option_value,
                                     const std::string& option, bool allow_reference);

// The haptic side for `mode` (ResolveHapticMode's) at `steps_per_frame` haptic steps per visual
// frame.
device::MultirateOptions MakeMultirateOptions(const Scene& scene, device::HapticMode mode,
                                              int steps_per_frame);

// The lcp friction solve's sweeps per haptic step: haptic.lcp_friction_sweeps with the friction
// law, 0 (friction rows refused, none made) with the others.
int LcpFrictionSweeps(const Scene& scene);

}  // namespace hapsim::config
