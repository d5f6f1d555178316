// `hapsim inspect SCENE [--frames N] [--json FILE]`: what a scene will simulate, before running
// it (DESIGN.md §9, "model no more than the scene needs"): each object, rigid or deformable, with
// its nodes, tets and DOFs (a rigid object has none: it builds no FEM), the tool, the contact law
// and the rates; then the memory the built model takes and the cost of a visual frame, both
// measured by building the scene and running its first frames (not estimated from formulas).

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "config/body_builder.h"
#include "config/scene.h"
#include "config/simulation_builder.h"
#include "contact/visual_frame.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/scripted_trajectory.h"
#include "core/statistics.h"
#include "core/stopwatch.h"
#include "device/multirate_simulator.h"
#include "fem/time_stepper.h"

namespace hapsim::apps {
namespace {

struct InspectOptions {
  std::string scene_path;
  int num_frames = 30;
  std::string json_path;  // empty: none
};

// Resident memory of this process, bytes (/proc/self/statm), or 0 where it cannot be read.
double ReadResidentBytes() {
  std::ifstream statm("/proc/self/statm");
  double total_pages = 0.0, resident_pages = 0.0;
  if (!(statm >> total_pages >> resident_pages)) return 0.0;
  return resident_pages * static_cast<double>(sysconf(_SC_PAGE_SIZE));
}

const char* ShapeName(ToolShape::Kind kind) {
  switch (kind) {
    case ToolShape::Kind::kSphere:
      return "sphere";
    case ToolShape::Kind::kCapsule:
      return "capsule";
    case ToolShape::Kind::kCylinder:
      return "cylinder";
    case ToolShape::Kind::kBox:
      return "box";
    case ToolShape::Kind::kMesh:
      return "mesh";
  }
  return "?";
}

nlohmann::json DescribeShape(const ToolShape& shape) {
  nlohmann::json json{{"shape", ShapeName(shape.kind)}};
  if (shape.kind == ToolShape::Kind::kBox) {
    json["half_extents_m"] = {shape.half_extents_m.x(), shape.half_extents_m.y(),
                              shape.half_extents_m.z()};
  } else if (shape.kind == ToolShape::Kind::kMesh) {
    json["triangles"] = shape.mesh.triangles.cols();
  } else {
    json["radius_m"] = shape.radius_m;
    if (shape.kind != ToolShape::Kind::kSphere) json["length_m"] = shape.length_m;
  }
  return json;
}

// A rigid object: its shape, and a dynamic one's mass (its six degrees of freedom are a rigid
// body's, not FEM dofs).
nlohmann::json DescribeRigidObject(const contact::RigidObject& rigid) {
  nlohmann::json object{{"name", rigid.name}, {"kind", "rigid"}, {"dofs", 0}};
  object.update(DescribeShape(rigid.shape));
  if (rigid.dynamic) {
    object["dynamic"] = true;
    object["mass_kg"] = rigid.mass_kg;
  }
  return object;
}

// The scene's objects and tool as they will be simulated (the body built).
nlohmann::json DescribeScene(const config::Scene& scene, const config::Body* body) {
  nlohmann::json objects = nlohmann::json::array();
  // A part's share of a merged surface (its points carried by the part's nodes), or of the
  // boundary when the surface is empty or holds none of the part's points.
  const auto describe_surface = [&](const fem::EmbeddedSurface& surface, bool given,
                                    const config::Body::Part& part) {
    const auto in_part = [&](int node) {
      return node >= part.first_node && node < part.first_node + part.num_nodes;
    };
    int points = 0, triangles = 0;
    if (given) {
      for (int p = 0; p < surface.num_points(); ++p) points += in_part(surface.nodes(0, p));
      for (int f = 0; f < surface.num_triangles(); ++f)
        triangles += in_part(surface.nodes(0, surface.triangles(0, f)));
    } else {
      std::vector<char> used(body->model.num_nodes(), 0);
      for (Eigen::Index f = 0; f < body->model.surface_triangles.cols(); ++f) {
        if (!in_part(body->model.surface_triangles(0, f))) continue;
        ++triangles;
        for (int k = 0; k < 3; ++k) used[body->model.surface_triangles(k, f)] = 1;
      }
      points = static_cast<int>(std::count(used.begin(), used.end(), 1));
    }
    return nlohmann::json{{"embedded", given}, {"points", points}, {"triangles", triangles}};
  };
  // Each deformable object's part of the one FEM system (config::Body::parts, in scene order).
  const auto describe_deformable = [&](const std::string& name, const config::BodyScene& source,
                                       const config::Body::Part& part) {
    int fixed_nodes = 0;
    for (int n = part.first_node; n < part.first_node + part.num_nodes; ++n)
      fixed_nodes += body->model.dof_is_fixed[3 * n] ? 1 : 0;
    const fem::FemOptions& fem = source.options;
    objects.push_back(
        {{"name", name},
         {"kind", "deformable"},
         {"nodes", part.num_nodes},
         {"tets", part.num_tets},
         {"dofs", 3 * part.num_nodes},
         {"fixed_nodes", fixed_nodes},
         {"elasticity", fem::ToString(fem.elasticity)},
         {"integrator", fem::ToString(fem.integrator)},
         {"solver", fem::ToString(fem.solver.kind)},
         {"youngs_modulus_Pa", source.material.youngs_modulus_Pa},
         {"collision_surface", describe_surface(body->model.collision_surface,
                                                source.collision_surface.has_value(), part)},
         {"visual_surface",
          describe_surface(body->visual_surface, source.visual_surface.has_value(), part)}});
  };
  if (body != nullptr) {
    describe_deformable(scene.body_name, *scene.body, body->parts[0]);
    for (size_t k = 0; k < scene.more_bodies.size(); ++k)
      describe_deformable(scene.more_bodies[k].name, scene.more_bodies[k].body, body->parts[k + 1]);
  }
  for (const config::RigidObjectScene& rigid : scene.rigid_objects)
    objects.push_back(DescribeRigidObject(rigid.object));
  nlohmann::json json{{"scene", scene.name},
                      {"visual_dt_s", scene.dt_s},
                      {"num_frames", scene.num_steps},
                      {"fem_built", body != nullptr},
                      {"fem_dofs", body != nullptr ? body->model.num_dofs() : 0},
                      {"deformable_objects", body != nullptr ? 1 + scene.more_bodies.size() : 0},
                      {"objects", objects}};
  if (scene.tool) {
    nlohmann::json tool = DescribeShape(scene.tool->model.shape);
    if (scene.tool->point) tool["shape"] = "point";  // a sphere of its radius in the frame
    tool["mass_kg"] = scene.tool->model.mass_kg;
    json["tool"] = tool;
    json["contact_law"] = contact::ToString(scene.contact.law);
    json["compliance"] = contact::ToString(scene.contact.compliance);
    json["haptic_rate_hz"] = scene.haptic.rate_hz;
    json["haptic_mode"] = device::ToString(scene.haptic.mode);
  }
  return json;
}

// Runs the first `num_frames` frames as `hapsim sim` would (the scripted device) and returns the
// first frame's time (it factors the system and precomputes the compliance) apart from the
// median and largest of the others, and the most contacts seen.
nlohmann::json MeasureFrames(const config::Scene& scene, const std::optional<config::Body>& body,
                             int num_frames) {
  std::vector<double> frame_s;
  int max_contacts = 0;
  if (scene.tool) {
    const contact::VisualFrameOptions options =
        device::SetUpFrameForMode(config::MakeVisualFrameOptions(scene), scene.haptic.mode,
                                  scene.dt_s, 1.0 / scene.haptic.rate_hz);
    contact::VisualFrame frame = config::MakeVisualFrame(scene, body, options);
    fem::State state = body ? fem::MakeRestState(body->model) : fem::State{};
    ToolState tool = scene.tool->initial_state;
    const ScriptedTrajectory trajectory(scene.trajectory);
    for (int k = 0; k < num_frames; ++k) {
      const contact::VisualFrameStats stats =
          frame.Step(trajectory.Sample(k * scene.dt_s), &state, &tool);
      frame_s.push_back(stats.total_s);
      max_contacts = std::max(max_contacts, stats.num_candidates);
    }
  } else if (body) {
    fem::TimeStepper stepper(body->model, scene.body->options, scene.dt_s, body->external_force_N);
    fem::State state = fem::MakeRestState(body->model);
    for (int k = 0; k < num_frames; ++k) frame_s.push_back(stepper.Step(&state).total_s);
  }
  if (frame_s.empty()) return nlohmann::json{{"frames_run", 0}};
  const double first_s = frame_s.front();
  if (frame_s.size() > 1) frame_s.erase(frame_s.begin());
  const double median_s = Median(frame_s);
  return {{"frames_run", num_frames},
          {"first_frame_ms", 1e3 * first_s},
          {"median_frame_ms", 1e3 * median_s},
          {"max_frame_ms", 1e3 * *std::max_element(frame_s.begin(), frame_s.end())},
          {"max_visual_rate_hz", median_s > 0.0 ? 1.0 / median_s : 0.0},
          {"max_contacts", max_contacts}};
}

void PrintReport(const nlohmann::json& report) {
  std::printf("scene %s: visual frame %.4g s (%.4g Hz), %d frames\n",
              report["scene"].get<std::string>().c_str(), report["visual_dt_s"].get<double>(),
              1.0 / report["visual_dt_s"].get<double>(), report["num_frames"].get<int>());
  for (const nlohmann::json& object : report["objects"]) {
    if (object["kind"] == "deformable") {
      std::printf(
          "  %-12s deformable: %d nodes, %d tets, %d DOFs (%d fixed nodes); %s, %s, %s solver\n",
          object["name"].get<std::string>().c_str(), object["nodes"].get<int>(),
          object["tets"].get<int>(), object["dofs"].get<int>(), object["fixed_nodes"].get<int>(),
          object["elasticity"].get<std::string>().c_str(),
          object["integrator"].get<std::string>().c_str(),
          object["solver"].get<std::string>().c_str());
      const auto surface_text = [](const nlohmann::json& surface) {
        return std::to_string(surface["points"].get<int>()) + " points, " +
               std::to_string(surface["triangles"].get<int>()) + " triangles" +
               (surface["embedded"].get<bool>() ? " (embedded in the tets)" : " (the boundary)");
      };
      std::printf("  %-12s   collision surface %s; visual %s\n", "",
                  surface_text(object["collision_surface"]).c_str(),
                  surface_text(object["visual_surface"]).c_str());
    } else if (object.contains("dynamic")) {
      std::printf(
          "  %-12s rigid %s, dynamic: %.4g kg, falls and is pushed (a rigid body; no FEM)\n",
          object["name"].get<std::string>().c_str(), object["shape"].get<std::string>().c_str(),
          object["mass_kg"].get<double>());
    } else {
      std::printf("  %-12s rigid %s: 0 DOFs, no FEM\n", object["name"].get<std::string>().c_str(),
                  object["shape"].get<std::string>().c_str());
    }
  }
  if (!report["fem_built"].get<bool>()) std::printf("  FEM: none built (no deformable object)\n");
  if (report["fem_dofs"].get<int>() > 0 && report["deformable_objects"].get<int>() > 1)
    std::printf("  FEM: one system of the %d deformable objects, %d DOFs\n",
                report["deformable_objects"].get<int>(), report["fem_dofs"].get<int>());
  if (report.contains("tool")) {
    std::printf(
        "  tool: %s, %.4g kg; contact %s, compliance %s; haptic %s at %.4g Hz\n",
        report["tool"]["shape"].get<std::string>().c_str(), report["tool"]["mass_kg"].get<double>(),
        report["contact_law"].get<std::string>().c_str(),
        report["compliance"].get<std::string>().c_str(),
        report["haptic_mode"].get<std::string>().c_str(), report["haptic_rate_hz"].get<double>());
  }
  std::printf("  memory: %.1f MiB resident for the built model and its first frames (measured)\n",
              report["model_memory_bytes"].get<double>() / (1 << 20));
  const nlohmann::json& cost = report["frame_cost"];
  if (cost["frames_run"].get<int>() > 0) {
    std::printf(
        "  frame cost over the first %d frames: the first %.3f ms (factor, precompute), then "
        "median %.3f ms, max %.3f ms (up to %.0f Hz on this machine), up to %d contacts\n",
        cost["frames_run"].get<int>(), cost["first_frame_ms"].get<double>(),
        cost["median_frame_ms"].get<double>(), cost["max_frame_ms"].get<double>(),
        cost["max_visual_rate_hz"].get<double>(), cost["max_contacts"].get<int>());
  }
}

void RunInspect(const InspectOptions& options) {
  const config::Scene scene = config::LoadScene(options.scene_path);
  const int num_frames = std::min(options.num_frames, scene.num_steps);
  const double resident_before = ReadResidentBytes();
  const std::optional<config::Body> body = config::MakeSceneBody(scene);
  nlohmann::json report = DescribeScene(scene, body ? &*body : nullptr);
  report["frame_cost"] = MeasureFrames(scene, body, num_frames);
  report["model_memory_bytes"] = std::max(0.0, ReadResidentBytes() - resident_before);
  PrintReport(report);
  if (!options.json_path.empty()) {
    WriteFileAtomically(options.json_path,
                        [&](std::ostream& out) { out << report.dump(2) << '\n'; });
    std::printf("  wrote %s\n", options.json_path.c_str());
  }
}

}  // namespace

void AddInspectCommand(CLI::App* app) {
  auto options = std::make_shared<InspectOptions>();
  CLI::App* inspect = app->add_subcommand(
      "inspect",
      "What a scene will simulate: each object (deformable: nodes, tets, DOFs; rigid: no FEM),\n"
      "the tool, contact law and rates; then the memory the built model takes and the cost of a\n"
      "visual frame, measured by building the scene and running its first frames.");
  inspect->add_option("scene", options->scene_path, "Scene file (YAML)")->required();
  inspect->add_option("--frames", options->num_frames, "Frames to run for the cost (default 30)")
      ->check(CLI::Range(1, 100000));
  inspect->add_option("--json", options->json_path, "Also write the report as JSON to FILE");
  inspect->callback([options] { RunInspect(*options); });
}

}  // namespace hapsim::apps
