#pragma once
// Real-time plumbing shared by the two processes of a run (issue 4): the monotonic clock, an
// absolute-deadline sleep, the request for SCHED_FIFO and locked memory, and a SIGINT/SIGTERM
// flag. Linux only (clock_nanosleep, sched_setscheduler, mlockall).

#include <array>
#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

namespace hapsim {

// CLOCK_MONOTONIC, ns.
std::int64_t MonotonicNs();
// Wall clock, µs since the Unix epoch (LCM's utime).
std::int64_t WallMicros();
// Sleeps until the monotonic time `deadline_ns` (absolute: no drift accumulates).
void SleepUntil(std::int64_t deadline_ns);

// Asks for SCHED_FIFO at `priority` and mlockall. Returns "" on success, else what failed (the
// caller warns and carries on with normal scheduling).
std::string RequestRealtime(int priority);

// What the kernel counted for the calling thread (getrusage RUSAGE_THREAD and its CPU clock).
// Between two readings they say why a late 1 kHz step was late: another task took the CPU
// (involuntary switches), the thread faulted memory in (page faults), or neither while the wall
// clock ran on past the thread's CPU time: the CPU was taken from the whole VM (the hypervisor's
// steal) or by interrupts, which no priority inside the guest can refuse.
struct ThreadCounters {
  std::int64_t cpu_ns = 0;  // CLOCK_THREAD_CPUTIME_ID
  long voluntary_switches = 0;
  long involuntary_switches = 0;
  long minor_faults = 0;
  long major_faults = 0;
};
ThreadCounters ReadThreadCounters();  // no allocation: safe in the 1 kHz loop

// An overrun (a step of a fixed-period loop that ended more than a period after its deadline) put
// down to one cause, the first that holds, from the loop thread's counters around the step's work:
//  - catching up: the step started behind, the step before it having ended after this one's
//    deadline, and its own work was short (one long step makes the next ones late too, until the
//    loop is back on its clock);
//  - preempted: another task took the CPU during the work (an involuntary switch; for a
//    SCHED_FIFO loop only a task of higher priority can);
//  - page faults: the work faulted memory in;
//  - blocked: the thread gave the CPU up during the work (a voluntary switch: a lock, a full
//    socket buffer, any system call that waits);
//  - held off: the work's wall time exceeds its CPU time by more than half a period with neither:
//    the hypervisor (steal, not counted as CPU time with PARAVIRT_TIME_ACCOUNTING) or interrupts
//    took the CPU from the whole VM;
//  - woke late: the work was short but the wake-up came more than half a period late (the timer
//    fired late, or the vCPU it fired on was not running);
//  - own work: the step's computation itself.
struct LateStepCauses {
  long catching_up = 0, preempted = 0, page_faults = 0, blocked = 0, held_off = 0, woke_late = 0,
       own_work = 0;
  double held_off_s = 0.0;  // the wall time the held-off steps spent off the CPU
  // started_behind: the previous step ended after this step's deadline; wake_late_s: this step's
  // start minus its deadline; work_wall_s: its work's wall time, between the readings `before`
  // and `after`; dt_s: the period.
  void Add(bool started_behind, double wake_late_s, double work_wall_s,
           const ThreadCounters& before, const ThreadCounters& after, double dt_s);
  long total() const {
    return catching_up + preempted + page_faults + blocked + held_off + woke_late + own_work;
  }
};

// The time the hypervisor took from this VM's CPUs, summed over them (/proc/stat "steal"), ns;
// -1 when it cannot be read. Allocates: call it before and after a loop, not in it.
std::int64_t ReadStealNs();

// SIGINT and SIGTERM set this flag (installed by InstallStopHandlers); loops poll it.
extern std::atomic<bool> g_stop_requested;
void InstallStopHandlers();

// Running quantiles of a timing error without allocation (for the 1 kHz loop's published
// statistics): 1 µs bins up to 5 ms, the last bin holding everything beyond.
class TimingHistogram {
 public:
  void Add(double error_s);
  // The upper edge of the bin holding quantile q, s (0 when empty). O(bins): call it sparingly.
  double Quantile(double q) const;
  double max_s() const { return max_s_; }

 private:
  static constexpr int kBins = 5001;
  std::array<long, kBins> bins_{};
  long count_ = 0;
  double max_s_ = 0.0;
};

}  // namespace hapsim
