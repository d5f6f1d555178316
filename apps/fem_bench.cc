#include "apps/fem_bench.h"

#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>

#include "apps/fem_run.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/progress_bar.h"
#include "core/statistics.h"

namespace hapsim::apps {
namespace {

struct SolverCase {
  const char* label;
  fem::SolverKind kind;
  fem::PreconditionerKind preconditioner;
  fem::FactorPrecision factor_precision = fem::FactorPrecision::kSingle;
};

// CHOLMOD first: its final state is the reference the others are measured against.
constexpr SolverCase kSolverCases[] = {
    {"cholmod", fem::SolverKind::kCholmod, fem::PreconditionerKind::kBlockJacobi},
    {"cg+lagged_cholesky", fem::SolverKind::kConjugateGradient,
     fem::PreconditionerKind::kLaggedCholesky},
    {"cg+lagged_cholesky_double", fem::SolverKind::kConjugateGradient,
     fem::PreconditionerKind::kLaggedCholesky, fem::FactorPrecision::kDouble},
    {"cg+lagged_cholesky_half", fem::SolverKind::kConjugateGradient,
     fem::PreconditionerKind::kLaggedCholesky, fem::FactorPrecision::kHalf},
    {"cg+block_jacobi", fem::SolverKind::kConjugateGradient, fem::PreconditionerKind::kBlockJacobi},
};

std::string ReadCpuModel() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; std::getline(cpuinfo, line);)
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown";
}

// Largest difference between two runs' probe trajectories, over all probes and steps, m.
double MaxProbeDifference(const FemRunRecord& a, const FemRunRecord& b) {
  double max_m = 0.0;
  for (size_t k = 0; k < a.probe_displacements_m.size(); ++k)
    max_m = std::max(
        max_m, (a.probe_displacements_m[k] - b.probe_displacements_m[k]).lpNorm<Eigen::Infinity>());
  return max_m;
}

double MaxProbeDisplacement(const FemRunRecord& record) {
  double max_m = 0.0;
  for (const Eigen::Matrix3Xd& u_m : record.probe_displacements_m)
    max_m = std::max(max_m, u_m.lpNorm<Eigen::Infinity>());
  return max_m;
}

// Runs one solver on one scene and returns its row. The accuracy columns compare its probe
// trajectory (every step, not only the last, which any convergent solver reaches once the body
// has settled) and its final state with `reference`'s; *record receives the run.
nlohmann::json MeasureCase(const config::Scene& scene, const config::Body& body,
                           const SolverCase& c, int num_steps, const FemRunRecord* reference,
                           FemRunRecord* record_out) {
  fem::FemOptions options = scene.body->options;
  options.integrator = fem::IntegratorKind::kImplicitEuler;
  options.solver.kind = c.kind;
  options.solver.preconditioner = c.preconditioner;
  options.solver.factor_precision = c.factor_precision;
  FemRunRecord& record = *record_out;
  {
    ProgressBar progress(scene.name + " " + c.label, num_steps);
    record = RunFem(body, options, scene.dt_s, num_steps, [&](int k) { progress.Update(k); });
  }
  std::vector<double> total, rotations, assembly, solve, iterations;
  for (const fem::StepStats& s : record.steps) {
    total.push_back(s.total_s), rotations.push_back(s.rotations_s),
        assembly.push_back(s.assembly_s);
    solve.push_back(s.solve_s), iterations.push_back(s.solve.iterations);
  }
  const double final_error_m =
      reference ? (record.final_state.x_m - reference->final_state.x_m).lpNorm<Eigen::Infinity>()
                : 0.0;
  const double probe_error_m = reference ? MaxProbeDifference(record, *reference) : 0.0;
  const double max_probe_m = MaxProbeDisplacement(record);
  return {{"scene", scene.name},
          {"num_tets", body.model.num_tets()},
          {"num_dofs", body.model.num_dofs()},
          {"solver", c.label},
          {"num_steps", num_steps},
          {"mean_ms", 1e3 * Mean(total)},
          {"median_ms", 1e3 * Median(total)},
          {"rotations_mean_ms", 1e3 * Mean(rotations)},
          {"assembly_mean_ms", 1e3 * Mean(assembly)},
          {"solve_mean_ms", 1e3 * Mean(solve)},
          {"iterations_mean", Mean(iterations)},
          {"num_factorizations", record.num_factorizations},
          {"max_probe_displacement_m", max_probe_m},
          {"probe_trajectory_difference_from_cholmod_m", probe_error_m},
          {"relative_difference_from_cholmod", max_probe_m > 0 ? probe_error_m / max_probe_m : 0.0},
          {"final_state_difference_from_cholmod_m", final_error_m}};
}

void PrintRow(const nlohmann::json& row) {
  std::printf("%-14s %7d %-26s %9.3f %9.3f %8.3f %8.3f %8.3f %7.1f %5d %11.2e\n",
              row["scene"].get<std::string>().c_str(), row["num_tets"].get<int>(),
              row["solver"].get<std::string>().c_str(), row["mean_ms"].get<double>(),
              row["median_ms"].get<double>(), row["rotations_mean_ms"].get<double>(),
              row["assembly_mean_ms"].get<double>(), row["solve_mean_ms"].get<double>(),
              row["iterations_mean"].get<double>(), row["num_factorizations"].get<int>(),
              row["relative_difference_from_cholmod"].get<double>());
}

void WriteBenchCsv(const std::string& path, const nlohmann::json& rows) {
  static const char* kColumns[] = {"scene",
                                   "num_tets",
                                   "num_dofs",
                                   "solver",
                                   "num_steps",
                                   "mean_ms",
                                   "median_ms",
                                   "rotations_mean_ms",
                                   "assembly_mean_ms",
                                   "solve_mean_ms",
                                   "iterations_mean",
                                   "num_factorizations",
                                   "max_probe_displacement_m",
                                   "probe_trajectory_difference_from_cholmod_m",
                                   "relative_difference_from_cholmod",
                                   "final_state_difference_from_cholmod_m"};
  WriteFileAtomically(path, [&](std::ostream& out) {
    for (size_t i = 0; i < std::size(kColumns); ++i) out << (i ? "," : "") << kColumns[i];
    out << '\n';
    for (const auto& row : rows) {
      for (size_t i = 0; i < std::size(kColumns); ++i) {
        const auto& value = row[kColumns[i]];
        out << (i ? "," : "") << (value.is_string() ? value.get<std::string>() : value.dump());
      }
      out << '\n';
    }
  });
}

}  // namespace

void RunFemBench(const FemBenchOptions& options) {
  nlohmann::json rows = nlohmann::json::array();
  std::printf("%-14s %7s %-26s %9s %9s %8s %8s %8s %7s %5s %11s\n", "scene", "tets", "solver",
              "mean_ms", "median_ms", "rot_ms", "asm_ms", "solve_ms", "iters", "facts",
              "probe_rel_err");
  for (const std::string& path : options.scene_paths) {
    const config::Scene scene = config::LoadScene(path);
    if (!scene.body)
      throw InputError(path, 0, "body", "the scene has no deformable body to benchmark");
    const config::Body body = config::MakeBody(*scene.body, scene.gravity_m_s2);
    const int num_steps = options.num_steps > 0 ? options.num_steps : scene.num_steps;
    if (body.probes.empty())
      throw InputError(path, 0, "body.probes", "--bench compares probe trajectories: add a probe");
    std::optional<FemRunRecord> reference;
    for (const SolverCase& c : kSolverCases) {
      FemRunRecord record;
      nlohmann::json row =
          MeasureCase(scene, body, c, num_steps, reference ? &*reference : nullptr, &record);
      if (!reference) reference = std::move(record);
      rows.push_back(row);
      PrintRow(row);
    }
  }
  const std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  const nlohmann::json summary = {{"machine", {{"cpu", ReadCpuModel()}, {"date", date}}},
                                  {"rows", rows}};
  CreateOutputDirectory(options.out_dir);
  const std::string summary_path =
      options.summary_path.empty() ? options.out_dir + "/fem_bench.json" : options.summary_path;
  WriteFileAtomically(summary_path, [&](std::ostream& out) { out << summary.dump(2) << '\n'; });
  WriteBenchCsv(options.out_dir + "/fem_bench.csv", rows);
  std::printf("wrote %s and %s/fem_bench.csv\n", summary_path.c_str(), options.out_dir.c_str());
}

}  // namespace hapsim::apps
