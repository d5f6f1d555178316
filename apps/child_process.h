#pragma once
// Another hapsim process started by this one (`run` starts `haptic`, `train` starts `run`): the
// same executable (/proc/self/exe) with other arguments, stopped with its parent.

#include <sys/types.h>

#include <string>
#include <vector>

namespace hapsim::apps {

// Starts this executable with `args` (args[0] is the program name shown in ps). The child gets
// SIGTERM when this process dies and inherits no descriptor beyond stdin, stdout and stderr
// (not this process's LCM sockets or log). Throws std::runtime_error when fork fails; an exec
// that fails makes the child exit 127 with a line on stderr naming `what`.
pid_t SpawnSelf(std::vector<std::string> args, const std::string& what);

// "" while the child runs; else how it ended ("exited with code 2", "was killed by signal
// Terminated"), with *exit_code its exit status (128 + signal when killed). Reaps the child.
std::string CheckChild(pid_t pid, int* exit_code);

}  // namespace hapsim::apps
