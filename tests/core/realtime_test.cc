// The overrun accounting of the 1 kHz loop (core/realtime.h): the thread counters it reads
// against what the kernel must count for work whose nature is known (a busy loop, a sleep, fresh
// memory touched), and the classification of a late step against hand-made counters, cause by
// cause and in its order of precedence.
#include "core/realtime.h"

#include <gtest/gtest.h>
#include <sys/mman.h>

#include <chrono>
#include <cstring>
#include <thread>

namespace hapsim {
namespace {

double SecondsBetween(std::int64_t from_ns, std::int64_t to_ns) { return 1e-9 * (to_ns - from_ns); }

TEST(ReadThreadCounters, ABusyLoopIsCpuTimeAndASleepIsNot) {
  // Busy for 30 ms of wall time: the thread's CPU time follows the wall clock (less what the host
  // or another task took: a fifth is a generous floor on a shared VM).
  ThreadCounters before = ReadThreadCounters();
  std::int64_t start_ns = MonotonicNs();
  volatile double sink = 0.0;
  while (MonotonicNs() - start_ns < 30000000) sink = sink + 1.0;
  ThreadCounters after = ReadThreadCounters();
  double wall_s = SecondsBetween(start_ns, MonotonicNs());
  double cpu_s = SecondsBetween(before.cpu_ns, after.cpu_ns);
  EXPECT_GT(cpu_s, 0.2 * wall_s);
  EXPECT_LE(cpu_s, wall_s + 1e-3);
  // Asleep for 30 ms: almost no CPU time, and at least one voluntary switch (the sleep itself).
  before = ReadThreadCounters();
  start_ns = MonotonicNs();
  SleepUntil(start_ns + 30000000);
  after = ReadThreadCounters();
  wall_s = SecondsBetween(start_ns, MonotonicNs());
  cpu_s = SecondsBetween(before.cpu_ns, after.cpu_ns);
  EXPECT_GE(wall_s, 0.03);
  EXPECT_LT(cpu_s, 0.5 * wall_s);
  EXPECT_GE(after.voluntary_switches, before.voluntary_switches + 1);
}

TEST(ReadThreadCounters, TouchingFreshMemoryCountsPageFaults) {
  constexpr size_t kBytes = 8 << 20;  // 2,048 small pages
  void* memory = mmap(nullptr, kBytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  ASSERT_NE(memory, MAP_FAILED);
  madvise(memory, kBytes, MADV_NOHUGEPAGE);  // one fault a 4 KiB page, not one a 2 MiB page
  const ThreadCounters before = ReadThreadCounters();
  for (size_t offset = 0; offset < kBytes; offset += 4096)
    static_cast<volatile char*>(memory)[offset] = 1;
  const ThreadCounters after = ReadThreadCounters();
  munmap(memory, kBytes);
  // Each page is faulted in at its first write (the kernel may map a few ahead: fault-around
  // applies to file pages, not to anonymous ones).
  EXPECT_GE(after.minor_faults + after.major_faults,
            before.minor_faults + before.major_faults + 1024);
}

TEST(ReadStealNs, IsReadableAndNeverDecreases) {
  const std::int64_t first = ReadStealNs();
  ASSERT_GE(first, 0) << "/proc/stat has no steal column";
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_GE(ReadStealNs(), first);
}

// Counters of a step's work: CPU time and the kernel's counts.
ThreadCounters Counters(double cpu_s, long involuntary, long faults) {
  ThreadCounters counters;
  counters.cpu_ns = static_cast<std::int64_t>(1e9 * cpu_s);
  counters.involuntary_switches = involuntary;
  counters.minor_faults = faults;
  return counters;
}

TEST(LateStepCauses, PutsEachOverrunDownToTheFirstCauseThatHolds) {
  constexpr double kDt = 1e-3;
  const ThreadCounters start = Counters(1.0, 10, 100);
  LateStepCauses causes;
  // Behind from the step before, with short work: catching up, whatever else the counters say.
  causes.Add(true, 0.9e-3, 0.1e-3, start, Counters(1.0001, 11, 101), kDt);
  EXPECT_EQ(causes.catching_up, 1);
  // Behind but long work: judged as any other step (here: preempted).
  causes.Add(true, 0.2e-3, 0.9e-3, start, Counters(1.0002, 11, 100), kDt);
  EXPECT_EQ(causes.preempted, 1);
  // A switch outranks faults and time off the CPU.
  causes.Add(false, 0.0, 2e-3, start, Counters(1.0001, 12, 105), kDt);
  EXPECT_EQ(causes.preempted, 2);
  // Faults without a switch.
  causes.Add(false, 0.0, 1.5e-3, start, Counters(1.0002, 10, 101), kDt);
  EXPECT_EQ(causes.page_faults, 1);
  // A voluntary switch (the thread waited), no preemption, no fault: blocked, not held off.
  ThreadCounters waited = Counters(1.0004, 10, 100);
  waited.voluntary_switches = start.voluntary_switches + 1;
  causes.Add(false, 0.0, 3e-3, start, waited, kDt);
  EXPECT_EQ(causes.blocked, 1);
  EXPECT_EQ(causes.held_off, 0);
  // Wall time 3 ms, CPU time 0.4 ms, no switch, no fault: held off the CPU for 2.6 ms.
  causes.Add(false, 0.0, 3e-3, start, Counters(1.0004, 10, 100), kDt);
  EXPECT_EQ(causes.held_off, 1);
  EXPECT_NEAR(causes.held_off_s, 2.6e-3, 1e-9);
  // Short work on the CPU after a wake-up 0.8 ms late.
  causes.Add(false, 0.8e-3, 0.3e-3, start, Counters(1.0003, 10, 100), kDt);
  EXPECT_EQ(causes.woke_late, 1);
  // On time, on the CPU all along, and long: the step's own work.
  causes.Add(false, 0.1e-3, 1.2e-3, start, Counters(1.0012, 10, 100), kDt);
  EXPECT_EQ(causes.own_work, 1);
  EXPECT_EQ(causes.total(), 8);
}

}  // namespace
}  // namespace hapsim
