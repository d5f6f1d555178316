#include "core/error.h"

#include <cstdio>
#include <cstdlib>

namespace hapsim {
namespace {

std::string FormatInputError(const std::string& file, int line, const std::string& key,
                             const std::string& message) {
  std::string text = file.empty() ? std::string("<input>") : file;
  if (line > 0) text += ":" + std::to_string(line);
  text += ": ";
  if (!key.empty()) text += "key '" + key + "': ";
  return text + message;
}

}  // namespace

InputError::InputError(const std::string& file, int line, const std::string& key,
                       const std::string& message)
    : std::runtime_error(FormatInputError(file, line, key, message)),
      file_(file),
      line_(line),
      key_(key) {}

void AbortOnFailedInvariant(const char* condition, const char* file, int line) {
  std::fprintf(stderr, "hapsim: internal invariant failed: %s at %s:%d\n", condition, file, line);
  std::abort();
}

}  // namespace hapsim
