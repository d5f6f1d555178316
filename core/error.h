#pragma once
// Errors that bad input can cause. They are always-on checks (the DRAKE_DEMAND kind): a user
// who feeds a wrong file gets a message naming the file, the line and the key, never a crash.

#include <stdexcept>
#include <string>

namespace hapsim {

// Thrown when user-supplied input (a scene file, a mesh file, a command-line value) is wrong.
// what() reads "FILE:LINE: key 'KEY': MESSAGE"; parts that are unknown are left out.
class InputError : public std::runtime_error {
 public:
  // line is 1-based; pass 0 when the line is unknown. key may be empty.
  InputError(const std::string& file, int line, const std::string& key, const std::string& message);

  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& key() const { return key_; }

 private:
  std::string file_;
  int line_;
  std::string key_;
};

// Internal invariant check, active in every build type: a broken invariant is a bug in hapsim,
// so it aborts with the condition and the source location instead of carrying on with garbage.
[[noreturn]] void AbortOnFailedInvariant(const char* condition, const char* file, int line);

}  // namespace hapsim

#define HAPSIM_INVARIANT(condition)   \
  ((condition) ? static_cast<void>(0) \
               : ::hapsim::AbortOnFailedInvariant(#condition, __FILE__, __LINE__))
