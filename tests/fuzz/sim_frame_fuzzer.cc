// Fuzz target: a SIM_FRAME datagram (sim_frame_t, the viewers' mesh and tool) decoded with
// messages::Decode. It has no validating adapter (nothing in hapsim acts on it); the target checks
// the bounded decoding alone.

#include <cstddef>
#include <cstdint>

#include "messages/adapters.h"
#include "tests/fuzz/message_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hapsim_lcm::sim_frame_t msg;
  hapsim::fuzz::DecodeMessage(data, size, &msg);
  return 0;
}
