#include "messages/message_gate.h"

#include <random>

namespace hapsim::messages {

std::string FormatRunId(std::int64_t run_id) {
  char text[17];
  std::snprintf(text, sizeof(text), "%016" PRIx64, static_cast<std::uint64_t>(run_id));
  return text;
}

bool ParseRunId(const std::string& text, std::int64_t* run_id) {
  std::string digits = text;
  if (digits.rfind("0x", 0) == 0 || digits.rfind("0X", 0) == 0) digits = digits.substr(2);
  if (digits.empty() || digits.size() > 16) return false;
  std::uint64_t value = 0;
  for (const char c : digits) {
    int digit = 0;
    if (c >= '0' && c <= '9')
      digit = c - '0';
    else if (c >= 'a' && c <= 'f')
      digit = c - 'a' + 10;
    else if (c >= 'A' && c <= 'F')
      digit = c - 'A' + 10;
    else
      return false;
    value = (value << 4) | static_cast<std::uint64_t>(digit);
  }
  if (value == 0) return false;
  *run_id = static_cast<std::int64_t>(value);
  return true;
}

std::int64_t MakeRunId() {
  std::random_device device;
  std::uint64_t value = 0;
  while (value == 0)
    value = (static_cast<std::uint64_t>(device()) << 32) ^ static_cast<std::uint64_t>(device());
  return static_cast<std::int64_t>(value);
}

}  // namespace hapsim::messages
