// Fuzz target: a DEVICE_STATE datagram (device_state_t) as the haptic process receives it,
// messages::Decode then messages::FromMessage. Non-finite values pass by design (the safety layer
// answers them with zero force); a finite pose it accepts has a unit quaternion.

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "messages/adapters.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/fuzz/message_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hapsim;
  hapsim_lcm::device_state_t msg;
  if (!fuzz::DecodeMessage(data, size, &msg)) return 0;
  DeviceState device;
  std::string error;
  if (!messages::FromMessage(msg, &device, &error)) {
    fuzz::CheckOrDie(!error.empty(), "device_state_t rejected without a reason");
    fuzz::Note(error);
    return 0;
  }
  if (device.q_WD.coeffs().allFinite())
    fuzz::CheckOrDie(
        std::abs(device.q_WD.norm() - 1.0) <= messages::kQuaternionNormTolerance,
        "device_state_t accepted a quaternion of norm " + std::to_string(device.q_WD.norm()));
  return 0;
}
