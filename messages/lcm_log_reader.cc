#include "messages/lcm_log_reader.h"

#include <filesystem>

#include "core/error.h"

namespace hapsim::messages {
namespace {

constexpr std::uint32_t kSyncWord = 0xEDA1DA01u;
constexpr std::int64_t kHeaderBytes = 4 + 8 + 8 + 4 + 4;

std::uint64_t BigEndian(const std::uint8_t* bytes, int count) {
  std::uint64_t value = 0;
  for (int i = 0; i < count; ++i) value = (value << 8) | bytes[i];
  return value;
}

}  // namespace

LcmLogReader::LcmLogReader(const std::string& path) : path_(path), file_(nullptr, &std::fclose) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw InputError(path, 0, "", "no such log file");
  size_ = static_cast<std::int64_t>(std::filesystem::file_size(path, error));
  file_.reset(std::fopen(path.c_str(), "rb"));
  if (error || !file_) throw InputError(path, 0, "", "cannot open as an LCM log");
}

void LcmLogReader::Corrupt(std::int64_t offset, const std::string& why) const {
  throw InputError(path_, 0, "",
                   "truncated or corrupt LCM log: the event at byte " + std::to_string(offset) +
                       " of " + std::to_string(size_) + " " + why + " (after " +
                       std::to_string(num_events_) + " complete events)");
}

bool LcmLogReader::Next(LcmLogEvent* event) {
  if (position_ == size_) return false;
  const std::int64_t start = position_;
  if (size_ - start < kHeaderBytes) Corrupt(start, "is cut inside its header");
  std::uint8_t header[kHeaderBytes];
  if (std::fread(header, 1, kHeaderBytes, file_.get()) != kHeaderBytes)
    Corrupt(start, "cannot be read");
  if (BigEndian(header, 4) != kSyncWord) Corrupt(start, "does not start with LCM's sync word");
  const auto channel_bytes = static_cast<std::int32_t>(BigEndian(header + 20, 4));
  const auto data_bytes = static_cast<std::int32_t>(BigEndian(header + 24, 4));
  if (channel_bytes <= 0 || channel_bytes > kMaxChannelBytes)
    Corrupt(start, "has a channel length of " + std::to_string(channel_bytes));
  if (data_bytes < 0) Corrupt(start, "has a negative data length");
  const std::int64_t remaining = size_ - start - kHeaderBytes;
  if (static_cast<std::int64_t>(channel_bytes) + data_bytes > remaining)
    Corrupt(start, "claims " + std::to_string(channel_bytes) + " + " + std::to_string(data_bytes) +
                       " bytes, " + std::to_string(remaining) + " remain");
  event->offset = start;
  event->event_number = static_cast<std::int64_t>(BigEndian(header + 4, 8));
  event->timestamp_us = static_cast<std::int64_t>(BigEndian(header + 12, 8));
  event->channel.resize(channel_bytes);
  event->data.resize(data_bytes);
  if (std::fread(event->channel.data(), 1, channel_bytes, file_.get()) !=
          static_cast<std::size_t>(channel_bytes) ||
      std::fread(event->data.data(), 1, data_bytes, file_.get()) !=
          static_cast<std::size_t>(data_bytes))
    Corrupt(start, "cannot be read");
  position_ = start + kHeaderBytes + channel_bytes + data_bytes;
  ++num_events_;
  return true;
}

}  // namespace hapsim::messages
