#pragma once
// Reads an LCM event log (hapsim run --log, lcm-logger) from untrusted bytes.
//
// Why not lcm::LogFile: LCM 1.3's reader mallocs an event's data length as read from the file and
// freads into it unchecked, so a log whose first event claims 2^31 − 1 bytes made `hapsim replay`
// segfault (issue 9). This reader checks every event's header against what remains of the file
// before allocating, and names the byte where a truncated or corrupt event starts.
//
// Format (lcm_eventlog.c), big-endian, event after event: int32 sync word 0xEDA1DA01, int64 event
// number, int64 timestamp (µs), int32 channel length, int32 data length, the channel's bytes (no
// NUL), the data.

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace hapsim::messages {

struct LcmLogEvent {
  std::int64_t event_number = 0;
  std::int64_t timestamp_us = 0;  // when the logger received it, µs since the Unix epoch
  std::string channel;
  std::vector<std::uint8_t> data;
  std::int64_t offset = 0;  // byte of the file where the event starts
};

class LcmLogReader {
 public:
  // LCM caps channel names at 63 characters; anything longer than this is corruption.
  static constexpr std::int64_t kMaxChannelBytes = 256;

  // Opens `path`. Throws hapsim::InputError naming it if it does not exist or cannot be read.
  explicit LcmLogReader(const std::string& path);

  // Reads the next event into *event (its buffers reused). Returns false at the end of the file.
  // Throws hapsim::InputError naming the file and the byte where an event is truncated or corrupt
  // (bad sync word, negative or oversized lengths, lengths beyond the end of the file).
  bool Next(LcmLogEvent* event);

  std::int64_t file_size() const { return size_; }
  long num_events() const { return num_events_; }

 private:
  [[noreturn]] void Corrupt(std::int64_t offset, const std::string& why) const;

  std::string path_;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file_;
  std::int64_t size_ = 0;
  std::int64_t position_ = 0;
  long num_events_ = 0;
};

}  // namespace hapsim::messages
