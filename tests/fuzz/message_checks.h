#pragma once
// The decoding every receiver of an LCM message does (messages::Decode: the bounded walk of
// wire_decode.h, then lcm-gen's decode()), with the agreements the message fuzz targets check on
// every input:
//  - the walk (CheckWireLayout) and decode() accept the same buffers: a buffer the walk passes
//    but decode() refuses would be a message lost without a reason, and one decode() would take
//    but the walk refuses is an error in the walk (decode() is only ever run after it);
//  - PeekRunId, which the log reader and the run filter use without decoding, reads the run id
//    that decode() reads.
// Decode promises never to throw: no try here, so an exception is a finding.

#include <climits>
#include <cstddef>
#include <cstdint>
#include <string>

#include "messages/wire_decode.h"
#include "tests/fuzz/fuzz_support.h"

namespace hapsim::fuzz {

template <typename T>
bool DecodeMessage(const std::uint8_t* data, std::size_t size, T* msg) {
  if (size > static_cast<std::size_t>(INT_MAX)) return false;
  const int n = static_cast<int>(size);
  std::string layout_error, decode_error;
  const bool layout_ok = messages::CheckWireLayout<T>(data, n, &layout_error);
  const bool decoded = messages::Decode(data, n, msg, &decode_error);
  CheckOrDie(decoded == layout_ok, std::string(T::getTypeName()) + ": the layout check " +
                                       (layout_ok ? "passed" : "failed: " + layout_error) +
                                       " but Decode " +
                                       (decoded ? "succeeded" : "failed: " + decode_error));
  if (!decoded) {
    Note(decode_error);
    return false;
  }
  std::int64_t run_id = 0;
  CheckOrDie(messages::PeekRunId(data, n, &run_id) && run_id == msg->run_id,
             std::string(T::getTypeName()) + ": PeekRunId disagrees with decode()");
  return true;
}

}  // namespace hapsim::fuzz
