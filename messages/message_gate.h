#pragma once
// The door every received hapsim message goes through before anything acts on it (issue 9):
// bounded decoding (wire_decode.h), then the run filter. A message that fails to decode is
// *rejected*; a well-formed message of another run is *foreign*. Both are counted, each kind is
// reported on stderr once per process (not per message: a second run beside this one sends
// 2,000 a second), and the counts go into the process's summary. Validation of the decoded
// values (finite, ranges, sizes) stays with the adapters (adapters.h), whose rejections the
// caller counts with CountRejected.
//
// Used from one receive thread per process; the counters are atomic so that the main thread may
// read them at the end (or while the run goes on) without a lock.

#include <atomic>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <string>

#include "messages/wire_decode.h"

namespace hapsim::messages {

class MessageGate {
 public:
  // process: names this process in the warnings ("hapsim haptic"); run_id: the run it serves
  // (0: not known yet, see AdoptRun).
  MessageGate(std::string process, std::int64_t run_id)
      : process_(std::move(process)), run_id_(run_id) {}

  // Decodes the message in `buffer` into *msg; true when it is well formed and of this run.
  template <typename T>
  bool Admit(const lcm::ReceiveBuffer* buffer, const std::string& channel, T* msg) {
    std::string error;
    if (!Decode(buffer->data, static_cast<int>(buffer->data_size), msg, &error)) {
      CountRejected(channel, error);
      return false;
    }
    return IsThisRun(msg->run_id, channel);
  }

  // True for this run's id; counts and reports (once) any other. A gate without a run yet
  // accepts nothing.
  bool IsThisRun(std::int64_t run_id, const std::string& channel) {
    const std::int64_t mine = run_id_.load();
    if (run_id == mine && mine != 0) return true;
    if (num_foreign_.fetch_add(1) == 0) {
      first_foreign_run_.store(run_id);
      std::fprintf(stderr,
                   "%s: warning: ignoring messages of another run on this LCM URL (run %016" PRIx64
                   " on %s; this run is %016" PRIx64
                   "). Two runs can share a URL; a station that wants its own traffic uses its "
                   "own --lcm-url (docs/DEVICE.md)\n",
                   process_.c_str(), static_cast<std::uint64_t>(run_id), channel.c_str(),
                   static_cast<std::uint64_t>(mine));
    }
    return false;
  }

  // Counts a message that failed decoding or validation; reports the first one.
  void CountRejected(const std::string& channel, const std::string& why) {
    if (num_rejected_.fetch_add(1) == 0)
      std::fprintf(stderr, "%s: warning: rejected a message on %s: %s (further ones are counted)\n",
                   process_.c_str(), channel.c_str(), why.c_str());
  }

  // A process that learns its run from the first message it hears (an external driver).
  void AdoptRun(std::int64_t run_id) { run_id_.store(run_id); }
  std::int64_t run_id() const { return run_id_.load(); }

  long num_foreign() const { return num_foreign_.load(); }
  long num_rejected() const { return num_rejected_.load(); }
  std::int64_t first_foreign_run() const { return first_foreign_run_.load(); }

 private:
  std::string process_;
  std::atomic<std::int64_t> run_id_;
  std::atomic<long> num_foreign_{0}, num_rejected_{0};
  std::atomic<std::int64_t> first_foreign_run_{0};
};

// A run id as printed and parsed on command lines: 16 hex digits.
std::string FormatRunId(std::int64_t run_id);
// Parses 1-16 hex digits (an optional 0x); false on anything else or on 0.
bool ParseRunId(const std::string& text, std::int64_t* run_id);
// A random non-zero run id (std::random_device).
std::int64_t MakeRunId();

}  // namespace hapsim::messages
