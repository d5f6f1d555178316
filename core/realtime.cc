#include "core/realtime.h"

#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <ctime>
#include <fstream>
#include <sstream>

namespace hapsim {

std::atomic<bool> g_stop_requested{false};

std::int64_t MonotonicNs() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

std::int64_t WallMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

void SleepUntil(std::int64_t deadline_ns) {
  timespec ts;
  ts.tv_sec = deadline_ns / 1000000000;
  ts.tv_nsec = deadline_ns % 1000000000;
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    if (g_stop_requested.load()) return;
  }
}

std::string RequestRealtime(int priority) {
  std::string failed;
  sched_param param{};
  param.sched_priority = priority;
  if (sched_setscheduler(0, SCHED_FIFO, &param) != 0)
    failed += std::string("SCHED_FIFO: ") + std::strerror(errno);
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
    failed += (failed.empty() ? "" : "; ") + std::string("mlockall: ") + std::strerror(errno);
  return failed;
}

ThreadCounters ReadThreadCounters() {
  ThreadCounters counters;
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  counters.cpu_ns = static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
  rusage usage{};
  if (getrusage(RUSAGE_THREAD, &usage) == 0) {
    counters.voluntary_switches = usage.ru_nvcsw;
    counters.involuntary_switches = usage.ru_nivcsw;
    counters.minor_faults = usage.ru_minflt;
    counters.major_faults = usage.ru_majflt;
  }
  return counters;
}

void LateStepCauses::Add(bool started_behind, double wake_late_s, double work_wall_s,
                         const ThreadCounters& before, const ThreadCounters& after, double dt_s) {
  const double off_cpu_s = work_wall_s - 1e-9 * static_cast<double>(after.cpu_ns - before.cpu_ns);
  if (started_behind && work_wall_s < 0.5 * dt_s) {
    ++catching_up;
  } else if (after.involuntary_switches > before.involuntary_switches) {
    ++preempted;
  } else if (after.minor_faults + after.major_faults > before.minor_faults + before.major_faults) {
    ++page_faults;
  } else if (after.voluntary_switches > before.voluntary_switches) {
    ++blocked;
  } else if (off_cpu_s > 0.5 * dt_s) {
    ++held_off;
    held_off_s += off_cpu_s;
  } else if (wake_late_s > 0.5 * dt_s) {
    ++woke_late;
  } else {
    ++own_work;
  }
}

std::int64_t ReadStealNs() {
  // "cpu  user nice system idle iowait irq softirq steal ...", in clock ticks (proc(5)).
  std::ifstream stat("/proc/stat");
  std::string line, label;
  if (!std::getline(stat, line)) return -1;
  std::istringstream fields(line);
  long long ticks[8];
  fields >> label;
  for (long long& t : ticks) fields >> t;
  if (!fields || label != "cpu") return -1;
  return ticks[7] * (1000000000LL / sysconf(_SC_CLK_TCK));
}

namespace {
void OnStopSignal(int) { g_stop_requested.store(true); }
}  // namespace

void InstallStopHandlers() {
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

void TimingHistogram::Add(double error_s) {
  const double us = std::max(0.0, 1e6 * error_s);
  ++bins_[us >= kBins - 1 ? kBins - 1 : static_cast<int>(us)];
  ++count_;
  max_s_ = std::max(max_s_, error_s);
}

double TimingHistogram::Quantile(double q) const {
  if (count_ == 0) return 0.0;
  const long rank = static_cast<long>(q * (count_ - 1));
  long seen = 0;
  for (int b = 0; b < kBins; ++b) {
    seen += bins_[b];
    if (seen > rank) return b == kBins - 1 ? max_s_ : 1e-6 * (b + 1);
  }
  return max_s_;
}

}  // namespace hapsim
