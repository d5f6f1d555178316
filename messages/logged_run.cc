#include "messages/logged_run.h"

#include <map>

#include "core/error.h"
#include "messages/lcm_log_reader.h"
#include "messages/message_gate.h"
#include "messages/wire_decode.h"

namespace hapsim::messages {

std::int64_t ChooseLoggedRun(const std::string& path, const std::string& requested) {
  std::map<std::int64_t, long> runs;  // hapsim messages per run id
  {
    LcmLogEvent event;
    LcmLogReader log(path);  // throws at a truncated or corrupt event, naming its byte
    std::int64_t run_id = 0;
    while (log.Next(&event))
      if (PeekRunId(event.data.data(), static_cast<int>(event.data.size()), &run_id))
        ++runs[run_id];
  }
  std::string listing;
  for (const auto& [id, count] : runs)
    listing += (listing.empty() ? "" : ", ") + FormatRunId(id) + " (" + std::to_string(count) +
               " messages)";
  if (!requested.empty()) {
    std::int64_t id = 0;
    if (!ParseRunId(requested, &id))
      throw InputError("--run-id", 0, "", "not 1-16 hex digits (and not 0): '" + requested + "'");
    if (!runs.count(id))
      throw InputError(path, 0, "--run-id",
                       "no run " + FormatRunId(id) + " in the log; it holds " + listing);
    return id;
  }
  if (runs.empty()) throw InputError(path, 0, "", "no hapsim messages in the log");
  if (runs.size() > 1)
    throw InputError(path, 0, "",
                     "the log holds " + std::to_string(runs.size()) + " runs: " + listing +
                         "; choose one with --run-id");
  return runs.begin()->first;
}

}  // namespace hapsim::messages
