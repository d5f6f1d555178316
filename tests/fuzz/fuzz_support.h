#pragma once
// Shared by the fuzz targets (tests/fuzz/*_fuzzer.cc): a scratch folder for the readers that take
// a path, and the line between an expected rejection and a finding.
//
// A target feeds bytes to one reader or decoder. Bad input must end in the error the reader's
// header promises (hapsim::InputError, or a false return from a decoder or a validator); anything
// else is a finding, and a finding must stop the process so that libFuzzer (or run_inputs_main.cc
// in the normal build) reports it: a crash, a sanitizer report, an uncaught exception, or a broken
// promise checked here (CheckOrDie).
//
// By default a std::exception other than InputError from a reader is accepted too (a clear error
// to the user, if not the named one). HAPSIM_FUZZ_STRICT=1 in the environment makes it a finding,
// to hunt for the errors that reach the user without a file, line and key.

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <typeinfo>

#include "core/error.h"

namespace hapsim::fuzz {

// Prints what broke and aborts: libFuzzer saves the input and prints the stack.
[[noreturn]] inline void Die(const std::string& what) {
  std::fprintf(stderr, "hapsim fuzz finding: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

inline void CheckOrDie(bool condition, const std::string& what) {
  if (!condition) Die(what);
}

// The folder for input files, made once per process and removed at exit: $HAPSIM_FUZZ_TMPDIR if
// set (scripts/fuzz.sh gives each run its own), else /dev/shm (memory: a file per execution costs
// microseconds there), else $TMPDIR or /tmp.
inline const std::string& ScratchDir() {
  static const std::string dir = [] {
    std::string parent;
    const char* const candidates[] = {std::getenv("HAPSIM_FUZZ_TMPDIR"), "/dev/shm",
                                      std::getenv("TMPDIR"), "/tmp"};
    for (const char* candidate : candidates) {
      if (candidate != nullptr && *candidate != '\0' && access(candidate, W_OK) == 0) {
        parent = candidate;
        break;
      }
    }
    if (parent.empty()) Die("no writable folder for input files");
    std::string pattern = parent + "/hapsim_fuzz_XXXXXX";
    if (mkdtemp(pattern.data()) == nullptr) Die("cannot create a folder in " + parent);
    static std::string made;  // for the exit handler, which takes no arguments
    made = pattern;
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(made, ignored);
    });
    return pattern;
  }();
  return dir;
}

// Writes `size` bytes to ScratchDir()/name (replacing it) and returns the path.
inline std::string WriteScratchFile(const std::string& name, const std::uint8_t* data,
                                    std::size_t size) {
  const std::string path = ScratchDir() + "/" + name;
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) Die("cannot write " + path);
  if (size > 0 && std::fwrite(data, 1, size, file) != size) Die("cannot write " + path);
  std::fclose(file);
  return path;
}

// HAPSIM_FUZZ_VERBOSE=1: print why each input was rejected (to check that seeds get past the
// first error; far too slow for fuzzing).
inline void Note(const std::string& what) {
  static const bool verbose = [] {
    const char* value = std::getenv("HAPSIM_FUZZ_VERBOSE");
    return value != nullptr && std::string(value) == "1";
  }();
  if (verbose) std::fprintf(stderr, "  rejected: %s\n", what.c_str());
}

inline bool StrictExceptions() {
  static const bool strict = [] {
    const char* value = std::getenv("HAPSIM_FUZZ_STRICT");
    return value != nullptr && std::string(value) == "1";
  }();
  return strict;
}

// Runs `read`, accepting the rejections a reader may answer bad input with (see the top of this
// file). Returns true if `read` returned normally.
template <typename Read>
bool RunReader(Read&& read) {
  try {
    read();
    return true;
  } catch (const InputError& e) {
    Note(e.what());
    return false;
  } catch (const std::exception& e) {
    if (StrictExceptions())
      Die(std::string("a reader threw ") + typeid(e).name() +
          " rather than InputError: " + e.what());
    Note(std::string(typeid(e).name()) + ": " + e.what());
    return false;
  }
}

}  // namespace hapsim::fuzz
