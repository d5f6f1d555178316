#pragma once
// Which run of an LCM log to read (`hapsim replay`, `hapsim view`): a log written by `hapsim run`
// holds one run, one recorded by the stock lcm-logger may hold several (issue 9).

#include <cstdint>
#include <string>

namespace hapsim::messages {

// The run id to read from the log at `path`: `requested` (--run-id, hex) or, when empty, the
// log's only run. Reads the log once, decoding nothing (a message's run id sits at a fixed
// place). Throws InputError naming the log: a corrupt event (its byte), no hapsim message,
// several runs and none requested (listing them), a requested run that is not there.
std::int64_t ChooseLoggedRun(const std::string& path, const std::string& requested);

}  // namespace hapsim::messages
