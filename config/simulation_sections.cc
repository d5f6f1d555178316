// The simulation sections of the scene schema (config/scene.h), read with the checked getters of
// config/yaml_reader.h. Checks involving more than one value are made here: exactly one tool shape
// and one of mass / density, the tool mesh on disk, friction_coefficient only with friction,
// whole haptic steps per visual frame, strictly increasing waypoint times, and which sections
// need which.

#include "config/simulation_sections.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "contact/tool_distance.h"
#include "core/rigid_tool.h"
#include "core/triangle_mesh_io.h"

namespace hapsim::config {
namespace {

namespace fs = std::filesystem;

constexpr contact::ComplianceMethod kComplianceMethods[] = {contact::ComplianceMethod::kWarped,
                                                            contact::ComplianceMethod::kExact};
constexpr contact::ModelComplianceStep kModelComplianceSteps[] = {
    contact::ModelComplianceStep::kVisual, contact::ModelComplianceStep::kHaptic,
    contact::ModelComplianceStep::kAuto};
constexpr ContactLaw kContactLaws[] = {ContactLaw::kEquality, ContactLaw::kUnilateral,
                                       ContactLaw::kFriction};
constexpr HapticMode kHapticModes[] = {
    HapticMode::kHybrid,   HapticMode::kLinear,    HapticMode::kLcp,
    HapticMode::kCoupling, HapticMode::kReference, HapticMode::kPenalty,
    HapticMode::kMaterial, HapticMode::kImpact,    HapticMode::kGodObject};

// (name, value) pairs for YamlMap::GetEnumOr, in declaration order.
template <typename Enum, std::size_t N>
std::vector<std::pair<std::string, Enum>> Choices(const Enum (&values)[N]) {
  std::vector<std::pair<std::string, Enum>> choices;
  for (const Enum value : values) choices.emplace_back(ToString(value), value);
  return choices;
}

template <typename Enum, std::size_t N>
std::optional<Enum> Parse(const Enum (&values)[N], const std::string& name) {
  for (const Enum value : values) {
    if (name == ToString(value)) return value;
  }
  return std::nullopt;
}

}  // namespace

SourceLocation LocationOf(const YamlMap& map) { return {map.file(), map.line(), map.path()}; }

MeshTransform ReadMeshTransform(const YamlMap& mesh) {
  MeshTransform transform;
  transform.scale = mesh.GetEnumOr<double>("units", {{"m", 1.0}, {"cm", 0.01}, {"mm", 0.001}}, 1.0);
  if (const std::optional<YamlMap> given = mesh.FindMap("transform")) {
    given->CheckKeys({"scale", "rotation_vector_rad", "translation_m"});
    transform.scale *= given->GetDoubleOr("scale", 1.0, Above(0.0));
    if (given->Has("rotation_vector_rad"))
      transform.rotation_vector_rad = given->GetVector3("rotation_vector_rad");
    if (given->Has("translation_m")) transform.translation_m = given->GetVector3("translation_m");
  }
  return transform;
}

std::string ResolveSurfaceFile(const YamlMap& map, const std::string& key,
                               const std::string& base_dir) {
  const fs::path given = map.GetString(key);
  const fs::path path = given.is_absolute() ? given : fs::path(base_dir) / given;
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension != ".obj" && extension != ".stl") {
    map.FailKey(key, "must be a Wavefront .obj or an .stl file, got '" + given.string() + "'");
  }
  std::error_code error;
  if (!fs::is_regular_file(path, error)) map.FailKey(key, "no such file: " + path.string());
  return path.string();
}

std::optional<EmbeddedSurfaceSource> ReadEmbeddedSurface(const YamlMap& body,
                                                         const std::string& key,
                                                         const std::string& base_dir) {
  const std::optional<YamlMap> map = body.FindMap(key);
  if (!map) return std::nullopt;
  map->CheckKeys({"file", "units", "transform"});
  EmbeddedSurfaceSource surface;
  surface.file = ResolveSurfaceFile(*map, "file", base_dir);
  surface.transform = ReadMeshTransform(*map);
  surface.location = LocationOf(*map);
  return surface;
}

namespace {

// The one shape of tool.shape. A mesh is read here (errors in it name the mesh file and line).
ToolShape ReadToolShape(const YamlMap& map, const std::string& base_dir, std::string* mesh_file) {
  map.CheckKeys({"sphere", "capsule", "cylinder", "box", "mesh"});
  const int num_shapes = map.Has("sphere") + map.Has("capsule") + map.Has("cylinder") +
                         map.Has("box") + map.Has("mesh");
  if (num_shapes != 1) {
    map.Fail("must give exactly one of sphere, capsule, cylinder, box, mesh; got " +
             std::to_string(num_shapes));
  }
  ToolShape shape;
  if (const std::optional<YamlMap> sphere = map.FindMap("sphere")) {
    sphere->CheckKeys({"radius_m"});
    shape.kind = ToolShape::Kind::kSphere;
    shape.radius_m = sphere->GetDouble("radius_m", Above(0.0));
  } else if (const std::optional<YamlMap> capsule = map.FindMap("capsule")) {
    capsule->CheckKeys({"radius_m", "length_m"});
    shape.kind = ToolShape::Kind::kCapsule;
    shape.radius_m = capsule->GetDouble("radius_m", Above(0.0));
    shape.length_m = capsule->GetDouble("length_m", AtLeast(0.0));
  } else if (const std::optional<YamlMap> cylinder = map.FindMap("cylinder")) {
    cylinder->CheckKeys({"radius_m", "length_m", "edge_radius_m"});
    shape.kind = ToolShape::Kind::kCylinder;
    shape.radius_m = cylinder->GetDouble("radius_m", Above(0.0));
    shape.length_m = cylinder->GetDouble("length_m", Above(0.0));
    shape.edge_radius_m = cylinder->GetDoubleOr(
        "edge_radius_m", 0.0, ClosedInterval(0.0, std::min(shape.radius_m, 0.5 * shape.length_m)));
  } else if (const std::optional<YamlMap> box = map.FindMap("box")) {
    box->CheckKeys({"half_extents_m"});
    shape.kind = ToolShape::Kind::kBox;
    shape.half_extents_m = box->GetVector3("half_extents_m", Above(0.0));
  } else {
    const YamlMap mesh = map.GetMap("mesh");
    mesh.CheckKeys({"file", "units", "transform"});
    shape.kind = ToolShape::Kind::kMesh;
    *mesh_file = ResolveSurfaceFile(mesh, "file", base_dir);
    shape.mesh = ReadTriangleMesh(*mesh_file);
    ReadMeshTransform(mesh).Apply(&shape.mesh.vertices_m);
  }
  return shape;
}

ToolScene ReadTool(const YamlMap& map, const std::string& base_dir) {
  map.CheckKeys(
      {"shape", "mass_kg", "density_kg_m3", "position_m", "rotation_vector_rad", "grasp"});
  ToolScene tool;
  tool.location = LocationOf(map);
  const YamlMap shape_map = map.GetMap("shape");
  ToolShape shape;
  if (shape_map.Has("point")) {  // a 3-DOF point of the god-object rendering: a small sphere
    shape_map.CheckKeys({"point"});
    const YamlMap point = shape_map.GetMap("point");
    point.CheckKeys({"radius_m"});
    shape.kind = ToolShape::Kind::kSphere;
    shape.radius_m = point.GetDouble("radius_m", Above(0.0));
    tool.point = true;
  } else {
    shape = ReadToolShape(shape_map, base_dir, &tool.mesh_file);
  }
  const int num_masses = map.Has("mass_kg") + map.Has("density_kg_m3");
  if (num_masses != 1) {
    map.Fail("must give exactly one of mass_kg, density_kg_m3; got " + std::to_string(num_masses));
  }
  const bool by_mass = map.Has("mass_kg");
  const double value =
      by_mass ? map.GetDouble("mass_kg", Above(0.0)) : map.GetDouble("density_kg_m3", Above(0.0));
  try {
    tool.model = by_mass ? MakeToolModelWithMass(std::move(shape), value)
                         : MakeToolModel(std::move(shape), value);
  } catch (const std::invalid_argument& error) {  // a shape the checks above let through
    shape_map.Fail(error.what());
  }
  tool.initial_state.x_W_m = map.GetVector3Or("position_m", Eigen::Vector3d::Zero());
  tool.initial_state.q_WT =
      CalcQuaternionExp(map.GetVector3Or("rotation_vector_rad", Eigen::Vector3d::Zero()));
  if (const std::optional<YamlMap> grasp = map.FindMap("grasp")) {
    grasp->CheckKeys({"jaw_center_m", "jaw_radius_m", "max_force_N"});
    contact::GraspOptions options;
    options.jaw_center_T_m = grasp->GetVector3("jaw_center_m");
    options.jaw_radius_m = grasp->GetDouble("jaw_radius_m", Above(0.0));
    options.max_force_N = grasp->GetDoubleOr("max_force_N", options.max_force_N, Above(0.0));
    tool.grasp = options;
  }
  return tool;
}

}  // namespace

contact::Material ReadContactMaterial(const YamlMap& map) {
  map.CheckKeys({"stiffness", "viscosity", "stickiness_N", "friction_N_m"});
  contact::Material material;
  material.stiffness = map.GetDoubleOr("stiffness", material.stiffness, ClosedInterval(0.0, 1.0));
  material.viscosity = map.GetDoubleOr("viscosity", material.viscosity, ClosedInterval(0.0, 1.0));
  material.stickiness_N = map.GetDoubleOr("stickiness_N", material.stickiness_N, AtLeast(0.0));
  material.friction_N_m = map.GetDoubleOr("friction_N_m", material.friction_N_m, AtLeast(0.0));
  return material;
}

namespace {

// `dynamic: true` with its mass (exactly one of mass_kg, density_kg_m3): the object's mass
// properties (contact/object_dynamics.h). A mesh is re-centred on its centre of mass, and its
// pose moved with it, so that the object stays where the scene put it.
void ReadObjectDynamics(const YamlMap& map, const std::string& name, contact::RigidObject* object) {
  object->dynamic = map.GetBoolOr("dynamic", false);
  const int num_masses = map.Has("mass_kg") + map.Has("density_kg_m3");
  if (!object->dynamic) {
    for (const char* key : {"mass_kg", "density_kg_m3"})
      if (map.Has(key))
        map.FailKey(key, "only a dynamic object has a mass (dynamic: true); " + name +
                             " is fixed, scripted or moved by the tool");
    return;
  }
  if (num_masses != 1)
    map.FailKey("dynamic", "the dynamic object " + name +
                               " needs its mass: give exactly one of mass_kg, density_kg_m3");
  if (object->script)
    map.FailKey("dynamic", "the dynamic object " + name +
                               " moves under gravity and its contacts, not by a trajectory");
  const bool by_mass = map.Has("mass_kg");
  const double value =
      by_mass ? map.GetDouble("mass_kg", Above(0.0)) : map.GetDouble("density_kg_m3", Above(0.0));
  const ToolShape shape = object->shape;
  const ToolModel model =
      by_mass ? MakeToolModelWithMass(shape, value) : MakeToolModel(shape, value);
  if (shape.kind == ToolShape::Kind::kMesh && shape.mesh.vertices_m.cols() > 0) {
    const Eigen::Vector3d com_O_m =
        shape.mesh.vertices_m.col(0) - model.shape.mesh.vertices_m.col(0);
    object->X_WO.translation() += object->X_WO.linear() * com_O_m;
  }
  object->shape = model.shape;
  object->mass_kg = model.mass_kg;
  object->inertia_O_kg_m2 = model.inertia_T_kg_m2;
}

}  // namespace

RigidObjectScene ReadRigidObject(const YamlMap& map, const std::string& name,
                                 const std::string& base_dir) {
  map.CheckKeys({"shape", "position_m", "rotation_vector_rad", "trajectory", "grabbable",
                 "friction_coefficient", "material", "dynamic", "mass_kg", "density_kg_m3"});
  RigidObjectScene rigid;
  rigid.location = LocationOf(map);
  rigid.object.name = name;
  const YamlMap shape_map = map.GetMap("shape");
  rigid.object.shape = ReadToolShape(shape_map, base_dir, &rigid.mesh_file);
  try {  // the distance field checks what the shape checks above cannot (an open mesh)
    contact::ToolDistanceField field(rigid.object.shape);
  } catch (const std::invalid_argument& error) {
    shape_map.Fail(error.what());
  }
  rigid.object.X_WO.translation() = map.GetVector3Or("position_m", Eigen::Vector3d::Zero());
  rigid.object.X_WO.linear() =
      CalcQuaternionExp(map.GetVector3Or("rotation_vector_rad", Eigen::Vector3d::Zero()))
          .toRotationMatrix();
  rigid.object.grabbable = map.GetBoolOr("grabbable", false);
  if (map.Has("friction_coefficient")) {
    rigid.object.friction_coefficient = map.GetDouble("friction_coefficient", AtLeast(0.0));
    rigid.friction_location = {map.file(), map.LineOf("friction_coefficient"),
                               map.KeyPath("friction_coefficient")};
  }
  if (const std::optional<YamlMap> material = map.FindMap("material"))
    rigid.material = ReadContactMaterial(*material);
  if (map.Has("trajectory")) {
    for (const char* key : {"position_m", "rotation_vector_rad"})
      if (map.Has(key))
        map.FailKey(key,
                    "give either a fixed pose (position_m, rotation_vector_rad) or a "
                    "trajectory, not both");
    if (rigid.object.grabbable)
      map.FailKey("grabbable", "an object moved by a script cannot be grabbed");
    rigid.object.script.emplace(ReadWaypoints(map, "trajectory", /*with_button=*/false));
    rigid.object.X_WO = contact::CalcScriptedPose(rigid.object, 0.0);
  }
  ReadObjectDynamics(map, name, &rigid.object);
  return rigid;
}

namespace {

CouplingParams ReadCoupling(const YamlMap& map) {
  map.CheckKeys({"k_lin_N_m", "b_lin_N_s_m", "k_ang_N_m_rad", "b_ang_N_m_s_rad"});
  CouplingParams coupling;
  coupling.k_lin_N_m = map.GetDouble("k_lin_N_m", AtLeast(0.0));
  coupling.b_lin_N_s_m = map.GetDouble("b_lin_N_s_m", AtLeast(0.0));
  coupling.k_ang_N_m_rad = map.GetDouble("k_ang_N_m_rad", AtLeast(0.0));
  coupling.b_ang_N_m_s_rad = map.GetDouble("b_ang_N_m_s_rad", AtLeast(0.0));
  return coupling;
}

ContactScene ReadContact(const YamlMap& map) {
  map.CheckKeys({"law", "friction_coefficient", "stabilization_beta", "restitution", "margin_m",
                 "compliance", "model_compliance_step", "tool_features"});
  ContactScene contact;
  contact.law = map.GetEnumOr("law", Choices(kContactLaws), contact.law);
  if (contact.law == ContactLaw::kFriction) {
    contact.friction_coefficient = map.GetDouble("friction_coefficient", AtLeast(0.0));
  } else if (map.Has("friction_coefficient")) {
    map.FailKey(
        "friction_coefficient",
        std::string("is used only with law: friction; the law is ") + ToString(contact.law));
  }
  contact.stabilization_beta =
      map.GetDoubleOr("stabilization_beta", contact.stabilization_beta, ClosedInterval(0.0, 1.0));
  contact.restitution =
      map.GetDoubleOr("restitution", contact.restitution, ClosedInterval(0.0, 1.0));
  contact.margin_m = map.GetDoubleOr("margin_m", contact.margin_m, AtLeast(0.0));
  contact.tool_features = map.GetBoolOr("tool_features", contact.tool_features);
  contact.compliance = map.GetEnumOr("compliance", Choices(kComplianceMethods), contact.compliance);
  contact.model_compliance_step = map.GetEnumOr(
      "model_compliance_step", Choices(kModelComplianceSteps), contact.model_compliance_step);
  return contact;
}

// The haptic steps per visual frame, rate_hz · dt_s, which must be a whole number ≥ 1. An error
// names haptic.rate_hz, or time.dt_s when the haptic section (and so the rate) is left out.
int CalcStepsPerFrame(double rate_hz, const YamlMap& time, const std::optional<YamlMap>& haptic) {
  constexpr double kWholeTolerance = 1e-9;  // dt_s = 1/60 written in decimal is off by ~1e-17
  const double steps = rate_hz * time.GetDouble("dt_s");
  const double whole = std::round(steps);
  if (whole >= 1.0 && whole <= 1e9 && std::abs(steps - whole) <= kWholeTolerance) {
    return static_cast<int>(whole);
  }
  std::ostringstream message;
  message << "haptic.rate_hz * time.dt_s = " << rate_hz << " * " << time.GetDouble("dt_s") << " = "
          << steps << " haptic steps per visual frame; it must be a whole number >= 1";
  if (haptic.has_value() && haptic->Has("rate_hz")) haptic->FailKey("rate_hz", message.str());
  time.FailKey("dt_s", message.str() + " (haptic.rate_hz is not given: 1000 Hz by default)");
}

device::SafetyLimits ReadSafety(const YamlMap& map) {
  map.CheckKeys({"max_force_N", "max_torque_N_m", "max_force_rate_N_s", "max_torque_rate_N_m_s",
                 "device_stale_s", "model_stale_s", "blend_time_s"});
  device::SafetyLimits limits;
  limits.max_force_N = map.GetDoubleOr("max_force_N", limits.max_force_N, Above(0.0));
  limits.max_torque_N_m = map.GetDoubleOr("max_torque_N_m", limits.max_torque_N_m, Above(0.0));
  limits.max_force_rate_N_s =
      map.GetDoubleOr("max_force_rate_N_s", limits.max_force_rate_N_s, Above(0.0));
  limits.max_torque_rate_N_m_s =
      map.GetDoubleOr("max_torque_rate_N_m_s", limits.max_torque_rate_N_m_s, Above(0.0));
  limits.device_stale_s = map.GetDoubleOr("device_stale_s", limits.device_stale_s, Above(0.0));
  limits.model_stale_s = map.GetDoubleOr("model_stale_s", limits.model_stale_s, Above(0.0));
  limits.blend_time_s = map.GetDoubleOr("blend_time_s", limits.blend_time_s, Above(0.0));
  return limits;
}

contact::PenaltyParams ReadPenalty(const YamlMap& map) {
  map.CheckKeys(
      {"stiffness_N_m", "predictive_margin", "max_force_change_N", "max_torque_change_N_m"});
  contact::PenaltyParams p;
  p.stiffness_N_m = map.GetDoubleOr("stiffness_N_m", p.stiffness_N_m, Above(0.0));
  p.predictive_margin = map.GetBoolOr("predictive_margin", p.predictive_margin);
  p.max_force_change_N = map.GetDoubleOr("max_force_change_N", p.max_force_change_N, Above(0.0));
  p.max_torque_change_N_m =
      map.GetDoubleOr("max_torque_change_N_m", p.max_torque_change_N_m, Above(0.0));
  return p;
}

// haptic.material: the device's k_max and b_max, and the tool's and the body's materials (each
// rigid object's is under its own `material`).
void ReadMaterialSection(const YamlMap& map, contact::MaterialParams* params) {
  map.CheckKeys({"max_stiffness_N_m", "max_damping_N_s_m", "tool", "body"});
  params->max_stiffness_N_m =
      map.GetDoubleOr("max_stiffness_N_m", params->max_stiffness_N_m, Above(0.0));
  params->max_damping_N_s_m =
      map.GetDoubleOr("max_damping_N_s_m", params->max_damping_N_s_m, AtLeast(0.0));
  if (const std::optional<YamlMap> tool = map.FindMap("tool"))
    params->tool = ReadContactMaterial(*tool);
  if (const std::optional<YamlMap> body = map.FindMap("body"))
    params->body = ReadContactMaterial(*body);
}

contact::GodObjectParams ReadGodObject(const YamlMap& map) {
  map.CheckKeys({"stiffness_N_m", "static_friction", "dynamic_friction", "shading",
                 "texture_amplitude_m", "texture_wavelength_m"});
  contact::GodObjectParams p;
  p.stiffness_N_m = map.GetDoubleOr("stiffness_N_m", p.stiffness_N_m, Above(0.0));
  p.static_friction = map.GetDoubleOr("static_friction", p.static_friction, AtLeast(0.0));
  p.dynamic_friction = map.GetDoubleOr("dynamic_friction", p.dynamic_friction, AtLeast(0.0));
  if (p.dynamic_friction > p.static_friction)
    map.FailKey("dynamic_friction",
                "must be <= static_friction (" + std::to_string(p.static_friction) + ")");
  p.shading = map.GetBoolOr("shading", p.shading);
  p.texture_amplitude_m =
      map.GetDoubleOr("texture_amplitude_m", p.texture_amplitude_m, AtLeast(0.0));
  p.texture_wavelength_m =
      map.GetDoubleOr("texture_wavelength_m", p.texture_wavelength_m, Above(0.0));
  return p;
}

// A row budget the 1 kHz solvers cannot hold is refused here, naming the key and the limit
// (issue 25):
//  - with the friction law a contact takes three rows, so fewer than three hold none: every
//    step with a contact fell back to the linear model (block_press_friction at 2 rows: 2,400 of
//    3,000 steps, peak 6.1 N against 3.7 N);
//  - each solver preallocates its rows' matrices, ≈ 16 n² bytes and 8 n² more with friction
//    (device/haptic_loop.h), and the haptic process holds four (its step's and the model
//    mailbox's three slots'): 100,000 rows ended in `std::bad_alloc` with no key named.
void CheckRowBudget(const YamlMap& map, int max_rows, ContactLaw law) {
  const int rows_per_contact = law == ContactLaw::kFriction ? 3 : 1;
  if (max_rows < rows_per_contact)
    map.FailKey("lcp_max_rows", std::to_string(max_rows) +
                                    " rows hold no contact of the friction law (3 rows each): "
                                    "at least 3");
  constexpr double kSolvers = 4.0;
  const double bytes_per_row_squared = law == ContactLaw::kFriction ? 24.0 : 16.0;
  const long pages = sysconf(_SC_PHYS_PAGES), page_bytes = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page_bytes <= 0) return;  // memory unknown: nothing to refuse on
  const double physical_bytes = static_cast<double>(pages) * static_cast<double>(page_bytes);
  const double rows = static_cast<double>(max_rows);
  if (kSolvers * bytes_per_row_squared * rows * rows > physical_bytes) {
    const long limit = static_cast<long>(
        std::floor(std::sqrt(physical_bytes / (kSolvers * bytes_per_row_squared))));
    char needed_gib[32];
    std::snprintf(needed_gib, sizeof(needed_gib), "%.3g",
                  kSolvers * bytes_per_row_squared * rows * rows / (1u << 30));
    map.FailKey("lcp_max_rows", std::to_string(max_rows) + " rows need " + needed_gib +
                                    " GiB in the haptic process's four solvers, more than this "
                                    "machine's memory: at most " +
                                    std::to_string(limit));
  }
}

HapticScene ReadHaptic(const std::optional<YamlMap>& map, const YamlMap& time, ContactLaw law) {
  HapticScene haptic;
  if (map.has_value()) {
    map->CheckKeys({"rate_hz", "mode", "lcp_max_rows", "lcp_friction_sweeps", "lcp_reach_m_s",
                    "safety", "penalty", "material", "impact", "godobject"});
    if (const std::optional<YamlMap> god = map->FindMap("godobject"))
      haptic.godobject = ReadGodObject(*god);
    if (const std::optional<YamlMap> penalty = map->FindMap("penalty"))
      haptic.geometric.penalty = ReadPenalty(*penalty);
    if (const std::optional<YamlMap> material = map->FindMap("material"))
      ReadMaterialSection(*material, &haptic.geometric.material);
    if (const std::optional<YamlMap> impact = map->FindMap("impact")) {
      impact->CheckKeys({"restitution"});
      haptic.geometric.impact.restitution = impact->GetDoubleOr(
          "restitution", haptic.geometric.impact.restitution, ClosedInterval(0.0, 1.0));
    }
    haptic.rate_hz = map->GetDoubleOr("rate_hz", haptic.rate_hz, Above(0.0));
    haptic.mode = map->GetEnumOr("mode", Choices(kHapticModes), haptic.mode);
    haptic.lcp_max_rows = map->GetIntOr("lcp_max_rows", haptic.lcp_max_rows, AtLeast(1));
    CheckRowBudget(*map, haptic.lcp_max_rows, law);
    if (map->Has("lcp_friction_sweeps") && law != ContactLaw::kFriction)
      map->FailKey("lcp_friction_sweeps", "the friction sweeps need contact.law: friction");
    haptic.lcp_friction_sweeps =
        map->GetIntOr("lcp_friction_sweeps", haptic.lcp_friction_sweeps, AtLeast(1));
    haptic.lcp_reach_m_s = map->GetDoubleOr("lcp_reach_m_s", haptic.lcp_reach_m_s, AtLeast(0.0));
    if (const std::optional<YamlMap> safety = map->FindMap("safety"))
      haptic.safety = ReadSafety(*safety);
  }
  haptic.steps_per_frame = CalcStepsPerFrame(haptic.rate_hz, time, map);
  return haptic;
}

device::HandParams ReadHand(const YamlMap& map) {
  map.CheckKeys({"mass_kg", "k_N_m", "b_N_s_m"});
  device::HandParams hand;
  hand.mass_kg = map.GetDoubleOr("mass_kg", hand.mass_kg, Above(0.0));
  hand.k_N_m = map.GetDoubleOr("k_N_m", hand.k_N_m, AtLeast(0.0));
  hand.b_N_s_m = map.GetDoubleOr("b_N_s_m", hand.b_N_s_m, AtLeast(0.0));
  return hand;
}

}  // namespace

std::vector<Waypoint> ReadWaypoints(const YamlMap& map, const std::string& key, bool with_button) {
  if (!map.Has(key)) map.FailKey(key, "missing required key");
  const std::vector<YamlMap> items = map.GetMapList(key);
  if (items.empty()) map.FailKey(key, "must hold at least one waypoint");
  std::vector<Waypoint> trajectory;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const YamlMap& item = items[i];
    if (with_button)
      item.CheckKeys({"t_s", "position_m", "rotation_vector_rad", "button"});
    else
      item.CheckKeys({"t_s", "position_m", "rotation_vector_rad"});
    Waypoint waypoint;
    if (with_button) waypoint.buttons = item.GetBoolOr("button", false) ? 1 : 0;
    waypoint.t_s = item.GetDouble("t_s", AtLeast(0.0));
    if (i > 0 && waypoint.t_s <= trajectory.back().t_s) {
      std::ostringstream message;
      message << "must be later than the waypoint before it (t_s " << trajectory.back().t_s
              << " on line " << items[i - 1].line() << "), got " << waypoint.t_s;
      item.FailKey("t_s", message.str());
    }
    waypoint.x_W_m = item.GetVector3("position_m");
    waypoint.q_WD =
        CalcQuaternionExp(item.GetVector3Or("rotation_vector_rad", Eigen::Vector3d::Zero()));
    trajectory.push_back(waypoint);
  }
  return trajectory;
}

namespace {

// What tool.grasp needs (config/scene.h): a body to hold, normal rows, contacts on the tets'
// boundary (a grasp takes boundary nodes, and an embedded collision surface's contacts around
// them would not be dropped), and a mode that renders the frame's rows or coupling.
void CheckGrasp(const Scene& scene, const YamlMap& root) {
  const YamlMap grasp = root.GetMap("tool").GetMap("grasp");
  if (!scene.body) grasp.Fail("a grasp needs a deformable body to hold; the scene has none");
  if (scene.contact.law == ContactLaw::kFriction)
    grasp.Fail(
        "a grasp's rows are normal rows: contact.law must be unilateral or equality, not "
        "friction");
  std::vector<std::pair<std::string, const BodyScene*>> bodies = {{scene.body_name, &*scene.body}};
  for (const DeformableObjectScene& more : scene.more_bodies)
    bodies.emplace_back(more.name, &more.body);
  for (const auto& [name, body] : bodies)
    if (body->collision_surface)
      grasp.Fail("a grasp holds the tets' boundary nodes; " + name +
                 " has a `collision:` surface, which is not supported with a grasp yet");
  if (const std::optional<std::string> why = WhyGraspRefused(scene.haptic.mode))
    root.GetMap("haptic").FailKey("mode", *why);
}

TaskScene ReadTask(const YamlMap& map, double duration_s) {
  map.CheckKeys({"targets", "force_band_N", "hold_s", "force_limit_N", "time_limit_s"});
  TaskScene task;
  for (const YamlMap& item : map.GetMapList("targets")) {
    item.CheckKeys({"name", "position_m", "radius_m"});
    PalpationTarget target;
    target.name = item.GetString("name");
    if (target.name.empty()) item.FailKey("name", "must not be empty");
    for (const PalpationTarget& other : task.targets) {
      if (other.name == target.name)
        item.FailKey("name", "duplicate target name '" + target.name + "' (first given on line " +
                                 std::to_string(other.location.line) + ")");
    }
    target.position_m = item.GetVector3("position_m");
    target.radius_m = item.GetDouble("radius_m", Above(0.0));
    target.location = LocationOf(item);
    task.targets.push_back(target);
  }
  if (task.targets.empty()) map.FailKey("targets", "needs at least one target");
  const Eigen::Vector2d band =
      map.GetVector2Or("force_band_N", Eigen::Vector2d(0.5, 2.0), AtLeast(0.0));
  if (!(band[0] < band[1])) map.FailKey("force_band_N", "must be [min, max] with min < max");
  task.force_band_min_N = band[0];
  task.force_band_max_N = band[1];
  task.hold_s = map.GetDoubleOr("hold_s", task.hold_s, Above(0.0));
  task.force_limit_N = map.GetDoubleOr("force_limit_N", task.force_limit_N, Above(band[1]));
  task.time_limit_s = map.GetDoubleOr("time_limit_s", duration_s, Above(0.0));
  return task;
}

}  // namespace

void ReadSimulationSections(const YamlMap& root, const YamlMap& time, const std::string& base_dir,
                            Scene* scene) {
  const std::optional<YamlMap> tool = root.FindMap("tool");
  if (!tool.has_value()) {
    for (const char* key : {"coupling", "contact", "haptic", "device", "task"}) {
      if (root.Has(key)) root.FailKey(key, "applies only to a scene with a tool; there is none");
    }
    return;
  }
  scene->tool = ReadTool(*tool, base_dir);
  for (const char* key : {"coupling", "device"}) {
    if (!root.Has(key)) {
      root.FailKey(key, "missing required key: the tool (line " + std::to_string(tool->line()) +
                            ") needs it");
    }
  }
  scene->coupling = ReadCoupling(root.GetMap("coupling"));
  if (const std::optional<YamlMap> contact = root.FindMap("contact")) {
    scene->contact = ReadContact(*contact);
  }
  scene->haptic = ReadHaptic(root.FindMap("haptic"), time, scene->contact.law);
  if (scene->haptic.mode == HapticMode::kGodObject && !scene->tool->point)
    root.GetMap("haptic").FailKey(
        "mode", "the godobject mode renders a 3-DOF point: give tool.shape.point {radius_m}");
  if (const std::optional<std::string> why = WhyModelComplianceStepRefused(
          scene->contact.model_compliance_step, scene->haptic.mode))
    root.GetMap("contact").FailKey("model_compliance_step", *why);
  if (scene->tool->grasp) CheckGrasp(*scene, root);
  const YamlMap device = root.GetMap("device");
  device.CheckKeys({"trajectory", "hand"});
  scene->trajectory = ReadWaypoints(device, "trajectory", /*with_button=*/true);
  if (const std::optional<YamlMap> hand = device.FindMap("hand")) scene->hand = ReadHand(*hand);
  if (const std::optional<YamlMap> task = root.FindMap("task"))
    scene->task = ReadTask(*task, scene->num_steps * scene->dt_s);
}

std::optional<ContactLaw> ParseContactLaw(const std::string& name) {
  return Parse(kContactLaws, name);
}

std::optional<contact::ComplianceMethod> ParseComplianceMethod(const std::string& name) {
  return Parse(kComplianceMethods, name);
}

std::optional<std::string> WhyModelComplianceStepRefused(contact::ModelComplianceStep step,
                                                         HapticMode mode) {
  if (step != contact::ModelComplianceStep::kHaptic || device::UsesLinearContactModel(mode))
    return std::nullopt;
  return std::string("'haptic' sets the linear contact model's compliance, which the ") +
         device::ToString(mode) + " mode does not use (hybrid, linear, lcp, reference)";
}

std::optional<std::string> WhyGraspRefused(HapticMode mode) {
  if (!device::NeedsWorld(mode)) return std::nullopt;  // the geometric modes and godobject
  return std::string("the ") + device::ToString(mode) +
         " mode finds its own contacts at 1 kHz and cannot render a grasp's rows (hybrid, "
         "linear, lcp, coupling, reference can)";
}

std::optional<HapticMode> ParseHapticMode(const std::string& name) {
  return Parse(kHapticModes, name);
}

}  // namespace hapsim::config
