// Fuzz target: a DEVICE_FORCE datagram (device_force_t) as a device backend receives it,
// messages::Decode then messages::FromMessage, which must pass only finite wrenches.

#include <cstddef>
#include <cstdint>

#include "messages/adapters.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/fuzz/message_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hapsim;
  hapsim_lcm::device_force_t msg;
  if (!fuzz::DecodeMessage(data, size, &msg)) return 0;
  Eigen::Vector3d force_W_N, torque_W_N_m;
  std::string error;
  if (!messages::FromMessage(msg, &force_W_N, &torque_W_N_m, &error)) {
    fuzz::CheckOrDie(!error.empty(), "device_force_t rejected without a reason");
    fuzz::Note(error);
    return 0;
  }
  fuzz::CheckOrDie(force_W_N.allFinite() && torque_W_N_m.allFinite(),
                   "device_force_t accepted a non-finite wrench");
  return 0;
}
