#pragma once
// `hapsim fem --bench`: time per implicit step for each scene and each solver, with the
// accuracy of each beside its speed (distance of its final state from the direct CHOLMOD solve).

#include <string>
#include <vector>

namespace hapsim::apps {

struct FemBenchOptions {
  std::vector<std::string> scene_paths;
  std::string out_dir;       // fem_bench.csv goes here
  std::string summary_path;  // default <out_dir>/fem_bench.json
  int num_steps = 0;         // 0: each scene's
};

void RunFemBench(const FemBenchOptions& options);

}  // namespace hapsim::apps
