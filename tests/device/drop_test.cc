// scenes/drop.yaml (issue 28, objects that fall): an instrument grabbed off a tray is let go over
// a soft pad, falls, and comes to rest in the tissue; then the probe presses it into the pad.
// Checked against statics that does not depend on the code: at rest the pad carries the
// instrument's weight m g (its mass from the scene file), and under the probe it carries m g plus
// the probe's push (the instrument in equilibrium between the two); the device, rendering at
// 1 kHz between frames, feels what the frames' response gives the tool.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "config/body_builder.h"
#include "config/scene.h"
#include "config/simulation_builder.h"
#include "contact/contact_jacobian.h"
#include "device/multirate_simulator.h"

namespace hapsim::device {
namespace {

constexpr int kInstrument = 1;  // the scene's second rigid object

// What one frame leaves: the instrument's state, the force the pad's nodes put on it, and the
// contact force on the tool, world.
struct DropFrame {
  double t_s = 0.0;
  Eigen::Vector3d x_W_m, v_W_m_s, pad_on_instrument_N, on_tool_N;
};

// The force the body's nodes put on object i: each body–object row pushes the node by λ along
// its direction and the object by −λ (friction rows: normal, t1, t2).
Eigen::Vector3d CalcBodyForceOnObject_N(const contact::VisualFrame& frame, int object) {
  Eigen::Vector3d force_N = Eigen::Vector3d::Zero();
  const int rows = frame.options().response.solve.law == contact::ContactLaw::kFriction ? 3 : 1;
  for (size_t i = 0; i < frame.contacts().size(); ++i) {
    const contact::Contact& contact = frame.contacts()[i];
    if (contact::KindOf(contact) != contact::ContactKind::kBodyObject ||
        contact.rigid_object != object)
      continue;
    Eigen::Vector3d directions[3] = {contact.n_W, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
    if (rows == 3) contact::CalcTangents(contact.n_W, &directions[1], &directions[2]);
    for (int d = 0; d < rows; ++d)
      force_N -= frame.impulses()[rows * static_cast<Eigen::Index>(i) + d] * directions[d];
  }
  return force_N;
}

TEST(Drop, InstrumentFallsRestsOnThePadWithItsWeightAndCarriesTheProbesPush) {
  const config::Scene scene = config::LoadScene("scenes/drop.yaml");
  const config::Body body = *config::MakeSceneBody(scene);
  const double mass_kg = scene.rigid_objects[kInstrument].object.mass_kg;
  const double weight_N = mass_kg * 9.81;
  MultirateSimulator simulator(
      &body.model, &scene.body->options, body.external_force_N, scene.tool->model,
      scene.tool->initial_state, config::MakeVisualFrameOptions(scene),
      config::MakeMultirateOptions(scene, HapticMode::kHybrid, scene.haptic.steps_per_frame));
  std::vector<DropFrame> frames;
  std::vector<HapticSample> samples;
  simulator.Run(
      ScriptedTrajectory(scene.trajectory),
      std::lround(scene.num_steps * scene.dt_s * scene.haptic.rate_hz),
      [&](const HapticSample& s) { samples.push_back(s); },
      [&](const FrameSample& s) {
        const contact::VisualFrame& frame = simulator.visual_frame();
        const ToolState& instrument = frame.dynamic_objects()[0].state;
        frames.push_back({s.t_s, instrument.x_W_m, instrument.v_W_m_s,
                          CalcBodyForceOnObject_N(frame, kInstrument), s.contact_force_W_N});
      });
  // Over a window of frames: the mean force of the pad on the instrument, its largest speed,
  // the mean force on the tool.
  const auto window = [&](double from_s, double to_s) {
    DropFrame mean;
    mean.pad_on_instrument_N.setZero();
    mean.on_tool_N.setZero();
    mean.v_W_m_s.setZero();
    int count = 0;
    for (const DropFrame& f : frames) {
      if (f.t_s < from_s || f.t_s >= to_s) continue;
      mean.pad_on_instrument_N += f.pad_on_instrument_N;
      mean.on_tool_N += f.on_tool_N;
      mean.x_W_m = f.x_W_m;
      if (f.v_W_m_s.norm() > mean.v_W_m_s.norm()) mean.v_W_m_s = f.v_W_m_s;
      ++count;
    }
    mean.pad_on_instrument_N /= count;
    mean.on_tool_N /= count;
    return mean;
  };
  // Let go at 5 s with its underside 25 mm above the pad; at rest on it from ~5.3 s until the
  // probe comes back down (6.5 s).
  const DropFrame rest = window(6.0, 6.4);
  std::printf(
      "resting on the pad: centre (%.4f, %.4f, %.5f) m, fastest %.2e m/s, pad force "
      "(%.5f, %.5f, %.5f) N; m g %.5f N\n",
      rest.x_W_m.x(), rest.x_W_m.y(), rest.x_W_m.z(), rest.v_W_m_s.norm(),
      rest.pad_on_instrument_N.x(), rest.pad_on_instrument_N.y(), rest.pad_on_instrument_N.z(),
      weight_N);
  EXPECT_NEAR(rest.x_W_m.x(), 0.025, 0.005);  // where it was let go, over the pad's centre
  EXPECT_NEAR(rest.x_W_m.y(), 0.0, 0.005);
  // Lying flat on the pad's top (15 mm), pressed in by its weight less than 2 mm.
  const double half_height_m = scene.rigid_objects[kInstrument].object.shape.half_extents_m.z();
  EXPECT_LT(rest.x_W_m.z(), 0.015 + half_height_m + 1e-4);
  EXPECT_GT(rest.x_W_m.z(), 0.015 + half_height_m - 0.002);
  EXPECT_LT(rest.v_W_m_s.norm(), 1e-3);
  EXPECT_NEAR(rest.pad_on_instrument_N.z(), weight_N, 1e-3 * weight_N);
  EXPECT_LT(rest.pad_on_instrument_N.head<2>().norm(), 1e-3 * weight_N);

  // Pressed and held (7.6 to 8 s): the pad carries the weight and the probe's push. The probe
  // pushes the instrument by −F_tool, so the instrument in equilibrium takes F_pad = m g + F_tool,z
  // from the pad.
  const DropFrame pressed = window(7.6, 8.0);
  Eigen::Vector3d felt_N = Eigen::Vector3d::Zero();
  int count = 0;
  for (const HapticSample& s : samples)
    if (s.t_s >= 7.6 && s.t_s < 8.0) felt_N += s.contact_force_W_N, ++count;
  felt_N /= count;
  std::printf(
      "pressed: pad force %.5f N against m g %.5f N + probe's push %.5f N = %.5f N; felt at "
      "1 kHz %.5f N; fastest %.2e m/s\n",
      pressed.pad_on_instrument_N.z(), weight_N, pressed.on_tool_N.z(),
      weight_N + pressed.on_tool_N.z(), felt_N.z(), pressed.v_W_m_s.norm());
  EXPECT_GT(pressed.on_tool_N.z(), 2.0 * weight_N);  // the probe pushes harder than its weight
  EXPECT_NEAR(pressed.pad_on_instrument_N.z(), weight_N + pressed.on_tool_N.z(),
              1e-3 * (weight_N + pressed.on_tool_N.z()));
  EXPECT_NEAR(felt_N.z(), pressed.on_tool_N.z(), 0.02 * pressed.on_tool_N.z());
}

}  // namespace
}  // namespace hapsim::device
