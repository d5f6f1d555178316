// Fuzz target: a RUN_INFO message (run_info_t) as `hapsim replay` reads it from a log:
// messages::Decode, then apps::LoadLoggedScene (apps/run_info.cc, compiled into this target), which
// checks the files the message names and parses its scene text against its folder. Errors there
// are InputErrors naming the file or the log.

#include <cstddef>
#include <cstdint>

#include "apps/run_info.h"
#include "messages/adapters.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/fuzz/message_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hapsim;
  hapsim_lcm::run_info_t info;
  if (!fuzz::DecodeMessage(data, size, &info)) return 0;
  fuzz::RunReader([&] { apps::LoadLoggedScene(info, "fuzz.lcm"); });
  return 0;
}
