#include "apps/child_process.h"

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <stdexcept>

namespace hapsim::apps {

pid_t SpawnSelf(std::vector<std::string> args, const std::string& what) {
  // Everything the child needs is built before fork: between fork and exec only
  // async-signal-safe calls (other threads may hold the allocator's locks).
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  const std::string exec_failed = "hapsim: exec of " + what + " failed\n";
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("cannot fork " + what);
  if (pid == 0) {
    prctl(PR_SET_PDEATHSIG, SIGTERM);   // the child stops if this process dies
    if (getppid() != parent) _exit(1);  // ... or has already died
    close_range(3, ~0U, 0);             // not this process's LCM sockets and log
    execv("/proc/self/exe", argv.data());
    [[maybe_unused]] const ssize_t ignored = write(2, exec_failed.data(), exec_failed.size());
    _exit(127);
  }
  return pid;
}

std::string CheckChild(pid_t pid, int* exit_code) {
  int status = 0;
  if (pid <= 0 || waitpid(pid, &status, WNOHANG) != pid) return "";
  if (WIFEXITED(status)) {
    *exit_code = WEXITSTATUS(status);
    return "exited with code " + std::to_string(*exit_code);
  }
  *exit_code = 128 + WTERMSIG(status);
  return std::string("was killed by signal ") + strsignal(WTERMSIG(status));
}

}  // namespace hapsim::apps
