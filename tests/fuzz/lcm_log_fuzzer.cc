// Fuzz target: an LCM event log read as `hapsim replay` reads it (apps/replay_command.cc ReadLog):
// messages::LcmLogReader over the file, each event's run id peeked, and the events of hapsim's
// channels decoded with messages::Decode. The reader throws InputError at a corrupt or truncated
// event; every event it returns must lie inside the file, after the previous one.

#include <cstddef>
#include <cstdint>

#include "messages/adapters.h"
#include "messages/channels.h"
#include "messages/lcm_log_reader.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/fuzz/message_checks.h"

namespace {

using namespace hapsim;

// LCM's event header: sync word, event number, timestamp, channel and data lengths.
constexpr std::int64_t kEventHeaderBytes = 4 + 8 + 8 + 4 + 4;

template <typename T>
void DecodeEvent(const messages::LcmLogEvent& event) {
  T msg;
  fuzz::DecodeMessage(event.data.data(), event.data.size(), &msg);
}

void ReadLog(const std::string& path, std::int64_t file_size) {
  messages::LcmLogReader log(path);
  fuzz::CheckOrDie(log.file_size() == file_size, "LcmLogReader: wrong file size");
  messages::LcmLogEvent event;
  std::int64_t end_of_previous = 0;
  while (log.Next(&event)) {
    const std::int64_t end = event.offset + kEventHeaderBytes +
                             static_cast<std::int64_t>(event.channel.size() + event.data.size());
    fuzz::CheckOrDie(event.offset >= end_of_previous && end <= file_size &&
                         static_cast<std::int64_t>(event.channel.size()) <=
                             messages::LcmLogReader::kMaxChannelBytes,
                     "LcmLogReader returned an event at byte " + std::to_string(event.offset) +
                         " outside the file or overlapping the previous one");
    end_of_previous = end;
    std::int64_t run_id = 0;
    messages::PeekRunId(event.data.data(), static_cast<int>(event.data.size()), &run_id);
    const std::string& channel = event.channel;
    if (channel == messages::kRunInfoChannel) {
      DecodeEvent<hapsim_lcm::run_info_t>(event);
    } else if (channel == messages::kDeviceStateChannel) {
      DecodeEvent<hapsim_lcm::device_state_t>(event);
    } else if (channel == messages::kHapticStateChannel) {
      DecodeEvent<hapsim_lcm::haptic_state_t>(event);
    } else if (channel == messages::kContactModelChannel) {
      DecodeEvent<hapsim_lcm::contact_model_t>(event);
    } else if (channel == messages::kDeviceForceChannel) {
      DecodeEvent<hapsim_lcm::device_force_t>(event);
    } else if (channel == messages::kSimFrameChannel) {
      DecodeEvent<hapsim_lcm::sim_frame_t>(event);
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = fuzz::WriteScratchFile("input.lcm", data, size);
  fuzz::RunReader([&] { ReadLog(path, static_cast<std::int64_t>(size)); });
  return 0;
}
