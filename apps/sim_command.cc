// `hapsim sim SCENE --mode M [--compliance C] [--visual-hz H] [--device scripted|hand] [--out DIR]
// [--summary FILE.json]`: the in-process multirate simulator (device/multirate_simulator.h) on a
// scene with a body, a tool and a scripted device or a simulated hand. Writes <out>/haptic.csv (one
// row per haptic step: device force and torque, tool pose, contacts in the model, model age, the
// passivity observer's energy), <out>/frames.csv (one row per visual frame: stage timings,
// contacts, solver figures, penetration of the tool and of the rigid objects, the visual tool's
// position and the frame's contact force on it) and a JSON summary; all after the run, atomically.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "apps/commands.h"
#include "apps/grasp_report.h"
#include "config/body_builder.h"
#include "config/scene.h"
#include "config/simulation_builder.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/progress_bar.h"
#include "core/statistics.h"
#include "device/multirate_simulator.h"

namespace hapsim::apps {
namespace {

struct SimCommandOptions {
  std::string scene_path;
  std::string mode;                 // empty: the scene's
  std::string compliance;           // empty: the scene's contact.compliance
  double visual_hz = 0.0;           // 0: the scene's (1 / time.dt_s)
  std::string device = "scripted";  // scripted (open loop) | hand (closed loop)
  std::string out_dir;              // default out/<scene name>_<mode>
  std::string summary_path;         // default <out>/summary.json
};

struct SimRecord {
  std::vector<device::HapticSample> haptic;
  std::vector<device::FrameSample> frames;
};

// Haptic steps per visual frame for a visual rate; throws naming the option if not a whole number.
int CalcStepsPerFrame(const config::Scene& scene, double visual_hz) {
  if (visual_hz <= 0.0) return scene.haptic.steps_per_frame;
  const double ratio = scene.haptic.rate_hz / visual_hz;
  const int steps = static_cast<int>(std::lround(ratio));
  if (steps < 1 || std::abs(ratio - steps) > 1e-9)
    throw InputError("", 0, "--visual-hz",
                     "the haptic rate (" + std::to_string(scene.haptic.rate_hz) +
                         " Hz) must be a whole multiple of the visual rate");
  return steps;
}

void WriteHapticCsv(const std::string& path, const SimRecord& record) {
  WriteFileAtomically(path, [&](std::ostream& out) {
    out << "t_s,force_x_N,force_y_N,force_z_N,torque_x_N_m,torque_y_N_m,torque_z_N_m,"
           "tool_x_m,tool_y_m,tool_z_m,tool_qw,tool_qx,tool_qy,tool_qz,contacts,model_age_s,"
           "lcp_fell_back,passivity_energy_J,device_x_m,device_y_m,device_z_m\n";
    for (const device::HapticSample& s : record.haptic) {
      const auto& f = s.device_force_W_N;
      const auto& t = s.device_torque_W_N_m;
      const auto& x = s.tool_x_W_m;
      const auto& q = s.tool_q_WT;
      out << s.t_s << ',' << f.x() << ',' << f.y() << ',' << f.z() << ',' << t.x() << ',' << t.y()
          << ',' << t.z() << ',' << x.x() << ',' << x.y() << ',' << x.z() << ',' << q.w() << ','
          << q.x() << ',' << q.y() << ',' << q.z() << ',' << s.num_contacts << ',' << s.model_age_s
          << ',' << s.lcp_fell_back << ',' << s.passivity_energy_J << ',' << s.device_x_W_m.x()
          << ',' << s.device_x_W_m.y() << ',' << s.device_x_W_m.z() << '\n';
    }
  });
}

// Open loop ("scripted"): the script is the device; closed loop ("hand"): a simulated hand pulled
// along the script feels the device force (device.hand), which is how an unstable rendering shows
// itself.
std::unique_ptr<device::DeviceBackend> MakeDevice(const config::Scene& scene,
                                                  const std::string& device) {
  if (device == "hand")
    return std::make_unique<device::SimulatedHand>(ScriptedTrajectory(scene.trajectory), scene.hand,
                                                   1.0 / scene.haptic.rate_hz);
  return std::make_unique<device::ScriptedDevice>(ScriptedTrajectory(scene.trajectory));
}

// What the grasper's jaws did over the run, a line each to stderr (apps/grasp_report.h).
void ReportGraspEvents(const config::Scene& scene, const SimRecord& record) {
  for (const device::FrameSample& f : record.frames) {
    const std::string grasp = DescribeGraspEvents(scene, f.t_s, f.stats);
    if (!grasp.empty()) std::fprintf(stderr, "hapsim sim: %s\n", grasp.c_str());
  }
}

void WriteFramesCsv(const std::string& path, const SimRecord& record) {
  WriteFileAtomically(path, [&](std::ostream& out) {
    out << "t_s,coupling_ms,free_tool_ms,free_fem_ms,detection_ms,response_ms,model_ms,sanity_ms,"
           "total_ms,candidates,contacts,active,solver_iterations,solver_residual,"
           "sanity_corrections,max_penetration_m,rigid_contacts,max_object_penetration_m,"
           "tool_x_m,tool_y_m,tool_z_m,contact_force_x_N,contact_force_y_N,contact_force_z_N,"
           "compliance_ms,solve_ms,correction_ms,grasped,grasp_slipped,grasp_drift_m\n";
    for (const device::FrameSample& f : record.frames) {
      const contact::VisualFrameStats& s = f.stats;
      out << f.t_s << ',' << 1e3 * s.coupling_s << ',' << 1e3 * s.free_tool_s << ','
          << 1e3 * s.free_fem_s << ',' << 1e3 * s.detection_s << ',' << 1e3 * s.response_s << ','
          << 1e3 * s.model_s << ',' << 1e3 * s.sanity_s << ',' << 1e3 * s.total_s << ','
          << s.num_candidates << ',' << s.num_contacts << ',' << s.num_active << ','
          << s.solve.iterations << ',' << s.solve.residual << ',' << s.num_sanity_corrections << ','
          << s.max_penetration_m << ',' << s.num_rigid_contacts << ',' << s.max_object_penetration_m
          << ',' << f.tool_x_W_m.x() << ',' << f.tool_x_W_m.y() << ',' << f.tool_x_W_m.z() << ','
          << f.contact_force_W_N.x() << ',' << f.contact_force_W_N.y() << ','
          << f.contact_force_W_N.z() << ',' << 1e3 * s.compliance_s << ',' << 1e3 * s.solve_s << ','
          << 1e3 * s.correction_s << ',' << s.num_grasped << ',' << s.num_grasp_slipped << ','
          << s.max_grasp_drift_m << '\n';
    }
  });
}

nlohmann::json MakeSummary(const config::Scene& scene, const std::string& mode,
                           const std::string& device, const contact::VisualFrameOptions& visual,
                           int steps_per_frame, const device::PassivityObserver& passivity,
                           const SimRecord& record) {
  std::vector<double> stage[8];
  double max_penetration_m = 0.0, max_object_penetration_m = 0.0;
  int max_contacts = 0;
  for (const device::FrameSample& f : record.frames) {
    const contact::VisualFrameStats& s = f.stats;
    const double values[8] = {s.coupling_s, s.free_tool_s, s.free_fem_s, s.detection_s,
                              s.response_s, s.model_s,     s.sanity_s,   s.total_s};
    for (int i = 0; i < 8; ++i) stage[i].push_back(1e3 * values[i]);
    max_penetration_m = std::max(max_penetration_m, s.max_penetration_m);
    max_object_penetration_m = std::max(max_object_penetration_m, s.max_object_penetration_m);
    max_contacts = std::max(max_contacts, s.num_contacts);
  }
  double peak_N = 0.0, sum_sq = 0.0, min_energy_J = 0.0;
  long lcp_fallbacks = 0;
  std::vector<double> step_us;
  step_us.reserve(record.haptic.size());
  for (const device::HapticSample& s : record.haptic) {
    step_us.push_back(1e6 * s.step_time_s);
    lcp_fallbacks += s.lcp_fell_back;
    peak_N = std::max(peak_N, s.device_force_W_N.norm());
    sum_sq += s.device_force_W_N.squaredNorm();
    min_energy_J = std::min(min_energy_J, s.passivity_energy_J);
  }
  static const char* kStages[8] = {"coupling", "free_tool", "free_fem", "detection",
                                   "response", "model",     "sanity",   "total"};
  nlohmann::json medians;
  for (int i = 0; i < 8; ++i) medians[kStages[i]] = Median(stage[i]);
  return {{"scene", scene.file},
          {"name", scene.name},
          {"mode", mode},
          {"haptic_rate_hz", scene.haptic.rate_hz},
          {"haptic_steps_per_frame", steps_per_frame},
          {"num_haptic_steps", record.haptic.size()},
          {"num_frames", record.frames.size()},
          {"contact_law", contact::ToString(scene.contact.law)},
          {"compliance", contact::ToString(visual.compliance)},
          // As the simulator resolved it (`auto` by the mode and the visual rate).
          {"model_compliance_step", contact::ToString(visual.model_compliance_step)},
          {"frame_stage_median_ms", medians},
          {"max_contacts", max_contacts},
          {"peak_force_N", peak_N},
          {"rms_force_N", record.haptic.empty() ? 0.0 : std::sqrt(sum_sq / record.haptic.size())},
          {"max_penetration_m", max_penetration_m},
          // deepest body node found inside a rigid object by a frame's sanity pass (then moved out)
          {"max_object_penetration_m", max_object_penetration_m},
          {"lcp_fallback_steps", lcp_fallbacks},
          // the haptic step alone (0 in reference and coupling: no 1 kHz work of their own)
          {"haptic_step_median_us", Median(step_us)},
          {"device", device},
          // energy flowed into the environment at the device port (< 0: it put energy out)
          {"passivity_min_energy_J", min_energy_J},
          {"passivity_final_energy_J",
           record.haptic.empty() ? 0.0 : record.haptic.back().passivity_energy_J},
          {"passivity_active_at_s",
           passivity.active()
               ? nlohmann::json(passivity.first_active_step() * (1.0 / scene.haptic.rate_hz))
               : nlohmann::json(nullptr)},
          {"haptic_step_max_us",
           step_us.empty() ? 0.0 : *std::max_element(step_us.begin(), step_us.end())}};
}

void RunSim(const SimCommandOptions& options) {
  config::Scene scene = config::LoadScene(options.scene_path);
  if (!options.compliance.empty()) {
    const auto parsed = config::ParseComplianceMethod(options.compliance);
    if (!parsed)
      throw InputError("", 0, "--compliance",
                       "unknown method '" + options.compliance + "' (warped, exact)");
    scene.contact.compliance = *parsed;
  }
  if (!scene.tool) throw InputError(scene.file, 0, "tool", "`hapsim sim` needs a tool");
  const device::HapticMode mode =
      config::ResolveHapticMode(scene, options.mode, "--mode", /*allow_reference=*/true);
  const device::MultirateOptions multirate =
      config::MakeMultirateOptions(scene, mode, CalcStepsPerFrame(scene, options.visual_hz));
  // A scene without a deformable body builds no FEM: the tool among its rigid objects.
  const std::optional<config::Body> body = config::MakeSceneBody(scene);
  device::MultirateSimulator simulator(
      body ? &body->model : nullptr, scene.body ? &scene.body->options : nullptr,
      body ? body->external_force_N : Eigen::VectorXd(), scene.tool->model,
      scene.tool->initial_state, config::MakeVisualFrameOptions(scene), multirate);
  const long num_steps = std::lround(scene.num_steps * scene.dt_s * scene.haptic.rate_hz);
  std::printf(
      "hapsim sim: %s, mode %s: %d tets, %zu rigid objects, %ld haptic steps at %g Hz, a visual "
      "frame every %d\n",
      scene.name.c_str(), device::ToString(mode), body ? body->model.num_tets() : 0,
      scene.rigid_objects.size(), num_steps, scene.haptic.rate_hz,
      multirate.haptic_steps_per_frame);
  SimRecord record;
  record.haptic.reserve(num_steps);
  {
    ProgressBar progress("sim", num_steps);
    const std::unique_ptr<device::DeviceBackend> backend = MakeDevice(scene, options.device);
    simulator.Run(
        backend.get(), num_steps,
        [&](const device::HapticSample& s) {
          record.haptic.push_back(s);
          progress.Update(static_cast<long>(record.haptic.size()));
        },
        [&](const device::FrameSample& f) { record.frames.push_back(f); });
  }
  ReportGraspEvents(scene, record);  // after the progress bar
  const std::string out_dir = options.out_dir.empty()
                                  ? "out/" + scene.name + "_" + device::ToString(mode)
                                  : options.out_dir;
  CreateOutputDirectory(out_dir);
  const std::string summary_path =
      options.summary_path.empty() ? out_dir + "/summary.json" : options.summary_path;
  CreateOutputDirectory(std::filesystem::path(summary_path).parent_path().string(), "--summary");
  WriteHapticCsv(out_dir + "/haptic.csv", record);
  WriteFramesCsv(out_dir + "/frames.csv", record);
  const nlohmann::json summary =
      MakeSummary(scene, device::ToString(mode), options.device, simulator.visual_options(),
                  multirate.haptic_steps_per_frame, simulator.passivity(), record);
  WriteFileAtomically(summary_path, [&](std::ostream& out) { out << summary.dump(2) << '\n'; });
  std::printf(
      "  peak force %.3f N, RMS %.3f N, max contacts %d, max penetration %.2f mm, median frame "
      "%.2f ms\n",
      summary["peak_force_N"].get<double>(), summary["rms_force_N"].get<double>(),
      summary["max_contacts"].get<int>(), 1e3 * summary["max_penetration_m"].get<double>(),
      summary["frame_stage_median_ms"]["total"].get<double>());
  // The rows a mode solves may outgrow haptic.lcp_max_rows at run time (more active contacts
  // than the load could foresee): those steps render the linear model instead, and a user must
  // learn it here rather than from a key of summary.json.
  if (const long fallbacks = summary["lcp_fallback_steps"].get<long>(); fallbacks > 0)
    std::fprintf(
        stderr,
        "hapsim sim: warning: %ld of %zu haptic steps rendered the linear model: their "
        "rows could not be solved (more than haptic.lcp_max_rows = %d, singular, or rejected)\n",
        fallbacks, record.haptic.size(), scene.haptic.lcp_max_rows);
  std::printf("  wrote %s/haptic.csv, %s/frames.csv, %s\n", out_dir.c_str(), out_dir.c_str(),
              summary_path.c_str());
}

}  // namespace

void AddSimCommand(CLI::App* app) {
  auto options = std::make_shared<SimCommandOptions>();
  CLI::App* sim = app->add_subcommand(
      "sim",
      "In-process multirate run of a scene: visual frames (FEM, contact, linear contact model) "
      "and\n"
      "1 kHz haptic steps, one after the other (bit-reproducible), following the scene's scripted\n"
      "device (or a simulated hand, --device hand). Writes haptic.csv, frames.csv and a JSON\n"
      "summary with the passivity observer's energy.");
  sim->add_option("scene", options->scene_path, "Scene file (YAML) with body, tool and device")
      ->required();
  sim->add_option(
      "--mode", options->mode,
      "hybrid (the paper's model with the frame's other candidate rows switched on at 1 kHz),\n"
      "linear (the paper's model alone), lcp (a unilateral solve on the frame's contact rows\n"
      "each haptic step), coupling (standard multirate), reference (all at the haptic rate, exact\n"
      "compliance); the source papers' other systems on the haptic tool at 1 kHz: penalty\n"
      "(k (eps + d), paper 000), material (Hooke + viscous + stick-slip, paper 003), impact\n"
      "(impulses with restitution, paper 001), godobject (a point tool's proxy, paper 004);\n"
      "default: the scene's haptic.mode, else hybrid");
  sim->add_option(
      "--compliance", options->compliance,
      "Body contact compliance: warped (precomputed at rest, warped by node rotations)\n"
      "or exact (forward solves with the step's factor); default: the scene's\n"
      "contact.compliance");
  sim->add_option(
         "--visual-hz", options->visual_hz,
         "Visual frame rate; the haptic rate must be a whole multiple (default: 1/time.dt_s)")
      ->check(CLI::PositiveNumber);
  sim->add_option("--device", options->device,
                  "scripted (default: the device follows the scene's script, open loop) or hand\n"
                  "(a simulated hand, the scene's device.hand mass-spring-damper, pulled along\n"
                  "the script and pushed by the device force: closed loop, for stability)")
      ->check(CLI::IsMember({"scripted", "hand"}));
  sim->add_option("--out", options->out_dir, "Output folder (default: out/<scene>_<mode>)");
  sim->add_option("--summary", options->summary_path,
                  "JSON summary file (default: <out>/summary.json)");
  sim->callback([options] { RunSim(*options); });
}

}  // namespace hapsim::apps
