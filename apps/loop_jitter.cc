// hapsim_loop_jitter: the host's floor for the haptic loop's timing. It runs the loop of
// `hapsim haptic` (absolute 1 kHz deadlines, SCHED_FIFO 80 and mlockall when permitted) with no
// work in it and prints the period error |period − 1 ms| quantiles. On a shared VM the host, not
// the code, sets this floor; scripts/bench_haptic.sh runs it beside every `hapsim run` so that
// the loop's figures can be read against a reference measured in the same minutes.
//
//   hapsim_loop_jitter [--steps N] [--summary FILE.json]

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/atomic_file.h"
#include "core/realtime.h"
#include "core/statistics.h"

int main(int argc, char** argv) {
  CLI::App app{"The haptic loop's timing floor on this host: an empty 1 kHz SCHED_FIFO loop."};
  long steps = 3000;
  std::string summary_path;
  app.add_option("--steps", steps, "Loop periods to measure")->check(CLI::Range(2L, 10000000L));
  app.add_option("--summary", summary_path, "Write the quantiles (µs) to this JSON file");
  CLI11_PARSE(app, argc, argv);
  const std::string rt_failure = hapsim::RequestRealtime(80);  // as `hapsim haptic`
  if (!rt_failure.empty())
    std::fprintf(stderr, "hapsim_loop_jitter: warning: normal scheduling (%s)\n", rt_failure.c_str());
  constexpr std::int64_t kPeriodNs = 1000000;
  std::vector<double> error_s;
  error_s.reserve(steps);
  std::int64_t deadline_ns = hapsim::MonotonicNs() + kPeriodNs, previous_ns = 0;
  for (long k = 0; k < steps; ++k) {
    hapsim::SleepUntil(deadline_ns);
    const std::int64_t now_ns = hapsim::MonotonicNs();
    if (k > 0) error_s.push_back(1e-9 * std::abs(static_cast<double>(now_ns - previous_ns - kPeriodNs)));
    previous_ns = now_ns;
    deadline_ns += kPeriodNs;
  }
  const nlohmann::json summary = {{"steps", steps},
                                  {"p50_us", 1e6 * hapsim::Quantile(error_s, 0.5)},
                                  {"p99_us", 1e6 * hapsim::Quantile(error_s, 0.99)},
                                  {"p999_us", 1e6 * hapsim::Quantile(error_s, 0.999)},
                                  {"max_us", 1e6 * hapsim::Quantile(error_s, 1.0)}};
  std::printf("empty 1 kHz loop, %ld periods: period error p50 %.1f us, p99 %.1f us, p99.9 %.1f us, "
              "max %.0f us\n", steps, summary["p50_us"].get<double>(), summary["p99_us"].get<double>(),
              summary["p999_us"].get<double>(), summary["max_us"].get<double>());
  if (!summary_path.empty()) {
    try {
      hapsim::WriteFileAtomically(summary_path,
                                  [&](std::ostream& out) { out << summary.dump(2) << "\n"; });
    } catch (const std::exception& error) {
      std::fprintf(stderr, "hapsim_loop_jitter: error: %s\n", error.what());
      return 1;
    }
  }
  return 0;
}
