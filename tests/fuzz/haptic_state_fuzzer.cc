// Fuzz target: a HAPTIC_STATE datagram (haptic_state_t) as the visual process and replay read it,
// messages::Decode then messages::HapticToolFromMessage (PoseFromMessage and the velocities),
// which must pass only a finite tool state with a unit quaternion.

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "messages/adapters.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/fuzz/message_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hapsim;
  hapsim_lcm::haptic_state_t msg;
  if (!fuzz::DecodeMessage(data, size, &msg)) return 0;
  ToolState tool;
  std::string error;
  if (!messages::HapticToolFromMessage(msg, &tool, &error)) {
    fuzz::CheckOrDie(!error.empty(), "haptic_state_t rejected without a reason");
    fuzz::Note(error);
    return 0;
  }
  fuzz::CheckOrDie(tool.x_W_m.allFinite() && tool.v_W_m_s.allFinite() &&
                       tool.L_W_kg_m2_s.allFinite() && tool.q_WT.coeffs().allFinite() &&
                       std::abs(tool.q_WT.norm() - 1.0) <= messages::kQuaternionNormTolerance,
                   "haptic_state_t accepted a non-finite tool state or a non-unit quaternion");
  return 0;
}
