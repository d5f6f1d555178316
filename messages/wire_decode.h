#pragma once
// Decoding of hapsim's LCM messages from untrusted bytes (a datagram from anyone on the LCM URL,
// an event of a log file), and the run a message belongs to.
//
// Why not lcm-gen's decode() alone: it trusts the count fields. For contact_model_t it calls
// `J_v.resize(num_rows)` before looking at how many bytes follow, so a 100-byte datagram saying
// num_rows = 10^8 allocates 2.4 GB (locked in memory by the haptic process's mlockall), and
// num_rows = −1 or a string length of 0 throws std::length_error through LCM's C dispatch, which
// terminates the process. Decode() first walks the wire layout, checking every count and string
// length against the bytes that remain, so decode() only ever runs on a message whose counts the
// buffer really holds; it also catches anything decode() still throws.
//
// Layout (LCM's encoding): an 8-byte type fingerprint, then the fields in .lcm order, big-endian;
// a string is an int32 length counting its terminating NUL, then the bytes. Every hapsim type
// starts with `int64_t utime; int64_t run_id;`, so the run id sits at bytes 16..23 of every
// message (PeekRunId relies on it; messages/*.lcm keep that order).

#include <cstdint>
#include <string>

#include "messages/adapters.h"

namespace hapsim::messages {

// Checks that `size` bytes at `data` are exactly one encoded T whose counts and string lengths fit
// (without decoding it). On failure returns false with the reason in *error (if not null).
template <typename T>
bool CheckWireLayout(const void* data, int size, std::string* error);

// lcm-gen's decode() resizes a variable array only when its count is non-zero: decoded into a
// reused message (the receive threads keep one, so that its vectors keep their storage), a
// count of 0 left the previous message's entries in place, and a contact model without rows
// after one with rows was rejected for its stale W_body_lower. This sizes every variable array
// to its count after decoding (shrinking keeps the storage: no allocation). Fixed-size types
// have none.
template <typename T>
void SizeArraysToCounts(T*) {}
template <>
void SizeArraysToCounts(hapsim_lcm::contact_model_t* msg);
template <>
void SizeArraysToCounts(hapsim_lcm::sim_frame_t* msg);
template <>
void SizeArraysToCounts(hapsim_lcm::run_info_t* msg);

// Decodes `size` bytes at `data` into *msg, consuming all of them: CheckWireLayout, then T's
// decode(), then SizeArraysToCounts. Never throws and never allocates beyond what the bytes
// hold. On failure returns false with the reason in *error and *msg in an unspecified (but
// valid) state.
template <typename T>
bool Decode(const void* data, int size, T* msg, std::string* error) {
  if (!CheckWireLayout<T>(data, size, error)) return false;
  try {
    if (msg->decode(data, 0, size) == size) {
      SizeArraysToCounts(msg);
      return true;
    }
    if (error != nullptr) *error = std::string(T::getTypeName()) + ": does not decode";
  } catch (const std::exception& e) {
    if (error != nullptr) *error = std::string(T::getTypeName()) + ": " + e.what();
  }
  return false;
}

// The run id of a message of one of hapsim's six types (by its fingerprint), without decoding it.
// Returns false for bytes of another type or too short to hold one.
bool PeekRunId(const void* data, int size, std::int64_t* run_id);

}  // namespace hapsim::messages
