// LiveRun (view/live_run.h), the run a live viewer hears, over an in-process LCM (memq://): when
// it counts the run as heard. `hapsim view` decides a run has ended when it has heard nothing of
// it for a while, so a message of either of the run's processes must count (a sanitized visual
// process's frames can be seconds apart while its haptic process publishes every millisecond),
// and neither another run's messages nor DEVICE_STATE (an external driver's, which may outlive
// the run) may.

#include "view/live_run.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "core/realtime.h"
#include "messages/channels.h"

namespace hapsim::view {
namespace {

constexpr std::int64_t kRunId = 0x5eed;
constexpr double kQuietS = 0.05;  // slept between messages

// A frame of a body-less scene: no nodes, contacts or objects, nothing selected or grabbed.
hapsim_lcm::sim_frame_t MakeEmptyFrame() {
  hapsim_lcm::sim_frame_t frame{};
  frame.selected_object = -1;
  frame.grabbed_object = -1;
  return frame;
}

class LiveRunTest : public ::testing::Test {
 protected:
  LiveRunTest() : lcm_("memq://"), live_(&lcm_, kRunId, "live_run_test") {}

  // Publishes `msg` of `run_id` on `channel` and lets the LiveRun handle it.
  template <typename T>
  void Deliver(const char* channel, T msg, std::int64_t run_id = kRunId) {
    msg.run_id = run_id;
    ASSERT_EQ(lcm_.publish(channel, &msg), 0);
    ASSERT_GT(lcm_.handleTimeout(1000), 0);
  }
  void Quiet() { std::this_thread::sleep_for(std::chrono::duration<double>(kQuietS)); }
  // Whether `deliver` made the run heard: the time since the run was last heard is then at most
  // the time since just before the delivery, read after it (exact, whatever the host's load).
  template <typename Deliver>
  bool Heard(Deliver deliver) {
    const std::int64_t before_ns = MonotonicNs();
    deliver();
    const double since_heard_s = live_.SecondsSinceLastMessage();
    return since_heard_s <= 1e-9 * static_cast<double>(MonotonicNs() - before_ns);
  }

  lcm::LCM lcm_;
  LiveRun live_;
};

TEST_F(LiveRunTest, FramesAndHapticStatesOfTheRunCountAsHeardNothingElseDoes) {
  EXPECT_TRUE(std::isinf(live_.SecondsSinceLastMessage()));  // nothing heard yet
  hapsim_lcm::run_info_t info{};
  info.haptic_rate_hz = 1000.0;
  Deliver(messages::kRunInfoChannel, info);
  ASSERT_NE(live_.timeline(), nullptr);

  EXPECT_TRUE(Heard([&] { Deliver(messages::kSimFrameChannel, MakeEmptyFrame()); }));
  EXPECT_TRUE(live_.timeline()->has_frames());

  // After the frame only the haptic process speaks (the visual one is inside a slow frame).
  Quiet();
  EXPECT_GE(live_.SecondsSinceLastMessage(), kQuietS);
  hapsim_lcm::haptic_state_t haptic{};
  haptic.step = 7;
  EXPECT_TRUE(Heard([&] { Deliver(messages::kHapticStateChannel, haptic); }));

  // A device's state alone is not the run: an external driver publishes it.
  Quiet();
  hapsim_lcm::device_state_t device{};
  device.sequence = 7;
  EXPECT_FALSE(Heard([&] { Deliver(messages::kDeviceStateChannel, device); }));
  EXPECT_GE(live_.SecondsSinceLastMessage(), kQuietS);

  // Another run on the same URL keeps nobody's run alive.
  EXPECT_FALSE(Heard([&] {
    Deliver(messages::kHapticStateChannel, haptic, kRunId + 1);
    Deliver(messages::kSimFrameChannel, MakeEmptyFrame(), kRunId + 1);
  }));
  EXPECT_GE(live_.SecondsSinceLastMessage(), kQuietS);
  EXPECT_EQ(live_.gate().num_foreign(), 2);
}

}  // namespace
}  // namespace hapsim::view
