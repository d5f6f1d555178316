// `hapsim fem SCENE [--out DIR] [--summary FILE.json] [--bench]`: a headless FEM-only run.
// Writes <out>/steps.csv (per-step stage timings, solver iterations, probe displacements),
// <out>/final_mesh.vtk (deformed mesh with displacement, opens in ParaView) and a JSON summary.
// Everything is computed first and written last, each file under a temporary name then renamed:
// a failed run leaves no half-written output.

#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "apps/fem_bench.h"
#include "apps/fem_run.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/progress_bar.h"
#include "core/statistics.h"
#include "fem/max_frequency.h"
#include "fem/mesh_io.h"

namespace hapsim::apps {
namespace {

struct FemCommandOptions {
  std::vector<std::string> scene_paths;
  std::string out_dir;       // default out/<scene name>
  std::string summary_path;  // default <out>/summary.json
  int num_steps = 0;         // 0: the scene's
  bool bench = false;
};

config::Scene LoadBodyScene(const std::string& path) {
  config::Scene scene = config::LoadScene(path);
  if (!scene.body)
    throw InputError(path, 0, "body", "the scene has no deformable body; `hapsim fem` needs one");
  // `fem` steps the deformable object alone: a body resting on a rigid object would fall through.
  if (!scene.rigid_objects.empty())
    throw InputError(path, scene.rigid_objects.front().location.line, "objects",
                     "the scene has rigid objects, which `hapsim fem` does not simulate; run it "
                     "with `hapsim sim` or `hapsim run`");
  if (!scene.more_bodies.empty())
    throw InputError(path, scene.more_bodies.front().location.line, "objects",
                     "`hapsim fem` steps one deformable object; this scene has " +
                         std::to_string(1 + scene.more_bodies.size()) +
                         " (run it with `hapsim sim` or `hapsim run`)");
  return scene;
}

std::vector<double> Column(const std::vector<fem::StepStats>& steps,
                           double fem::StepStats::*field) {
  std::vector<double> values;
  for (const fem::StepStats& s : steps) values.push_back(s.*field);
  return values;
}

nlohmann::json StageSummary(const std::vector<double>& seconds) {
  return {{"median_ms", 1e3 * Median(seconds)}, {"mean_ms", 1e3 * Mean(seconds)}};
}

nlohmann::json MakeSummary(const config::Scene& scene, const config::Body& body,
                           const FemRunRecord& record, int num_steps) {
  const fem::FemOptions& options = scene.body->options;
  std::vector<double> iterations, residuals;
  for (const fem::StepStats& s : record.steps) {
    iterations.push_back(s.solve.iterations);
    residuals.push_back(s.solve.relative_residual);
  }
  nlohmann::json probes = nlohmann::json::array();
  for (size_t p = 0; p < body.probes.size(); ++p) {
    const Eigen::Vector3d u_m =
        record.probe_displacements_m.back().col(static_cast<Eigen::Index>(p));
    probes.push_back(
        {{"name", body.probes[p].name}, {"final_displacement_m", {u_m.x(), u_m.y(), u_m.z()}}});
  }
  nlohmann::json summary = {
      {"scene", scene.file},
      {"name", scene.name},
      {"num_nodes", body.model.num_nodes()},
      {"num_tets", body.model.num_tets()},
      {"num_dofs", body.model.num_dofs()},
      {"num_fixed_nodes", body.model.num_fixed_nodes()},
      {"num_steps", num_steps},
      {"dt_s", scene.dt_s},
      {"elasticity", fem::ToString(options.elasticity)},
      {"integrator", fem::ToString(options.integrator)},
      {"solver", fem::ToString(options.solver.kind)},
      {"preconditioner", fem::ToString(options.solver.preconditioner)},
      {"factor_precision", fem::ToString(options.solver.factor_precision)},
      {"timings",
       {{"rotations", StageSummary(Column(record.steps, &fem::StepStats::rotations_s))},
        {"assembly", StageSummary(Column(record.steps, &fem::StepStats::assembly_s))},
        {"solve", StageSummary(Column(record.steps, &fem::StepStats::solve_s))},
        {"total", StageSummary(Column(record.steps, &fem::StepStats::total_s))}}},
      {"solver_iterations",
       {{"median", Median(iterations)},
        {"mean", Mean(iterations)},
        {"max", *std::max_element(iterations.begin(), iterations.end())}}},
      {"max_relative_residual", *std::max_element(residuals.begin(), residuals.end())},
      {"num_factorizations", record.num_factorizations},
      {"probes", probes}};
  if (options.integrator == fem::IntegratorKind::kExplicitEuler) {
    // Where the explicit step must fail: above 2 / ω_max, less with the material's damping.
    const fem::MaxFrequencyEstimate estimate = fem::EstimateMaxFrequency(body.model);
    const fem::Material& material = body.model.material;
    summary["omega_max_rad_s"] = estimate.omega_max_rad_s;
    summary["explicit_stable_dt_undamped_s"] = 2.0 / estimate.omega_max_rad_s;
    summary["explicit_stable_dt_s"] = fem::CalcExplicitStableStep(
        estimate.omega_max_rad_s, material.rayleigh_alpha_1_s, material.rayleigh_beta_s);
  }
  return summary;
}

void WriteStepsCsv(const std::string& path, const config::Body& body, const FemRunRecord& record,
                   double dt_s) {
  WriteFileAtomically(path, [&](std::ostream& out) {
    out << "step,time_s,rotations_ms,assembly_ms,solve_ms,total_ms,solver_iterations,relative_"
           "residual";
    for (const config::BoundProbe& probe : body.probes)
      out << ',' << probe.name << "_ux_m," << probe.name << "_uy_m," << probe.name << "_uz_m";
    out << '\n';
    for (size_t k = 0; k < record.steps.size(); ++k) {
      const fem::StepStats& s = record.steps[k];
      out << k + 1 << ',' << (k + 1) * dt_s << ',' << 1e3 * s.rotations_s << ','
          << 1e3 * s.assembly_s << ',' << 1e3 * s.solve_s << ',' << 1e3 * s.total_s << ','
          << s.solve.iterations << ',' << s.solve.relative_residual;
      const Eigen::Matrix3Xd& u_m = record.probe_displacements_m[k];
      for (Eigen::Index p = 0; p < u_m.cols(); ++p)
        out << ',' << u_m(0, p) << ',' << u_m(1, p) << ',' << u_m(2, p);
      out << '\n';
    }
  });
}

void RunFemOnce(const FemCommandOptions& options) {
  if (options.scene_paths.size() != 1)
    throw InputError("", 0, "SCENE", "give exactly one scene (several only with --bench)");
  const config::Scene scene = LoadBodyScene(options.scene_paths[0]);
  const config::Body body = config::MakeBody(*scene.body, scene.gravity_m_s2);
  const int num_steps = options.num_steps > 0 ? options.num_steps : scene.num_steps;
  std::printf(
      "hapsim fem: %s: %d nodes, %d tets, %d fixed nodes; %d steps of %.6g s (%s, %s, %s)\n",
      scene.name.c_str(), body.model.num_nodes(), body.model.num_tets(),
      body.model.num_fixed_nodes(), num_steps, scene.dt_s,
      fem::ToString(scene.body->options.elasticity), fem::ToString(scene.body->options.integrator),
      fem::ToString(scene.body->options.solver.kind));
  FemRunRecord record;
  {
    ProgressBar progress("fem", num_steps);
    record = RunFem(body, scene.body->options, scene.dt_s, num_steps,
                    [&](int k) { progress.Update(k); });
  }
  const std::string out_dir = options.out_dir.empty() ? "out/" + scene.name : options.out_dir;
  const std::string summary_path =
      options.summary_path.empty() ? out_dir + "/summary.json" : options.summary_path;
  CreateOutputDirectory(out_dir);
  WriteStepsCsv(out_dir + "/steps.csv", body, record, scene.dt_s);
  const Eigen::Map<const Eigen::Matrix3Xd> x_m(record.final_state.x_m.data(), 3,
                                               body.model.num_nodes());
  const Eigen::Matrix3Xd u_m = x_m - body.model.mesh.rest_positions_m;
  fem::WriteVtkTetMesh(x_m, body.model.mesh.tets, {{"displacement_m", &u_m}},
                       out_dir + "/final_mesh.vtk");
  const nlohmann::json summary = MakeSummary(scene, body, record, num_steps);
  CreateOutputDirectory(std::filesystem::path(summary_path).parent_path().string(), "--summary");
  WriteFileAtomically(summary_path, [&](std::ostream& out) { out << summary.dump(2) << '\n'; });
  std::printf(
      "  step time: median %.3f ms, mean %.3f ms (rotations %.3f, assembly %.3f, solve %.3f ms "
      "median)\n",
      summary["timings"]["total"]["median_ms"].get<double>(),
      summary["timings"]["total"]["mean_ms"].get<double>(),
      summary["timings"]["rotations"]["median_ms"].get<double>(),
      summary["timings"]["assembly"]["median_ms"].get<double>(),
      summary["timings"]["solve"]["median_ms"].get<double>());
  for (const auto& probe : summary["probes"])
    std::printf("  probe %s: final displacement %s m\n", probe["name"].get<std::string>().c_str(),
                probe["final_displacement_m"].dump().c_str());
  std::printf("  wrote %s/steps.csv, %s/final_mesh.vtk, %s\n", out_dir.c_str(), out_dir.c_str(),
              summary_path.c_str());
}

}  // namespace

void AddFemCommand(CLI::App* app) {
  auto options = std::make_shared<FemCommandOptions>();
  CLI::App* fem = app->add_subcommand(
      "fem",
      "Headless FEM-only run of a scene's deformable body from rest: writes per-step timings and\n"
      "probe displacements (CSV), a JSON summary and the final mesh (legacy VTK, for ParaView).");
  fem->add_option("scene", options->scene_paths, "Scene file (YAML); several with --bench")
      ->required();
  fem->add_option("--out", options->out_dir, "Output folder (default: out/<scene name>)");
  fem->add_option(
      "--summary", options->summary_path,
      "JSON summary file (default: <out>/summary.json; with --bench: <out>/fem_bench.json)");
  fem->add_option("--steps", options->num_steps,
                  "Number of steps (default: the scene's time.num_steps)")
      ->check(CLI::PositiveNumber);
  fem->add_flag("--bench", options->bench,
                "Benchmark each scene with every solver (CG + lagged Cholesky with its factor in\n"
                "single and in double precision, CG + block Jacobi, CHOLMOD): per-stage times and\n"
                "the difference of each final state from CHOLMOD's");
  fem->callback([options] {
    if (options->bench) {
      RunFemBench({options->scene_paths, options->out_dir.empty() ? "out/bench" : options->out_dir,
                   options->summary_path, options->num_steps});
    } else {
      RunFemOnce(*options);
    }
  });
}

}  // namespace hapsim::apps
