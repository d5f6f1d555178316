// The scene schema (documented in config/scene.h), read top to bottom with the checked getters of
// config/yaml_reader.h. Range checks that involve more than one value (box max > min, exactly one
// mesh source, unique probe names, the mesh file on disk) are made here; the simulation sections
// (tool, coupling, contact, haptic, device) are read in simulation_sections.cc.

#include "config/scene.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

#include "config/simulation_sections.h"
#include "config/yaml_reader.h"
#include "core/error.h"

namespace hapsim::config {
namespace {

namespace fs = std::filesystem;

// Reads min_m and max_m. Requires max > min on every axis, or max ≥ min when `allow_flat` (a box
// of zero thickness still selects the nodes on a plane).
AxisAlignedBox ReadBox(const YamlMap& map, bool allow_flat) {
  AxisAlignedBox box;
  box.min_m = map.GetVector3("min_m");
  box.max_m = map.GetVector3("max_m");
  for (int axis = 0; axis < 3; ++axis) {
    const double min = box.min_m[axis];
    const double max = box.max_m[axis];
    if (max < min || (!allow_flat && max == min)) {
      std::ostringstream message;
      message << "must be " << (allow_flat ? ">=" : ">") << " min_m on every axis; on axis "
              << "xyz"[axis] << " max is " << max << " and min is " << min;
      map.FailKey("max_m", message.str());
    }
  }
  return box;
}

// Resolves `file` against base_dir and checks that the mesh (and, for TetGen, its .ele) exists.
std::string ReadMeshFile(const YamlMap& mesh, const std::string& base_dir) {
  const fs::path given = mesh.GetString("file");
  const fs::path path = given.is_absolute() ? given : fs::path(base_dir) / given;
  const std::string extension = path.extension().string();
  if (extension != ".msh" && extension != ".node" && extension != ".vtk") {
    mesh.FailKey("file", "must be a Gmsh .msh, TetGen .node or legacy VTK .vtk file, got '" +
                             given.string() + "'");
  }
  std::error_code error;
  if (!fs::is_regular_file(path, error)) mesh.FailKey("file", "no such file: " + path.string());
  fs::path elements = path;
  elements.replace_extension(".ele");
  if (extension == ".node" && !fs::is_regular_file(elements, error)) {
    mesh.FailKey("file",
                 "a TetGen mesh needs its elements too; no such file: " + elements.string());
  }
  return path.string();
}

// A lattice's size checked before anything is allocated: 100000^3 cells once ended in
// `std::bad_alloc` with no key named. The estimate is a lower bound of what hapsim holds per tet
// (rest shape matrices, the 12x12 element stiffness, rotations: ~1.5 kB) and per node (state
// vectors and a sparse system row of ~27 neighbouring 3x3 blocks with its factor: ~4 kB), so only
// a scene that certainly cannot fit is refused. Node indices are ints: beyond 2^31 it is refused
// as well.
void CheckLatticeFitsMemory(const YamlMap& map, const std::string& key,
                            const Eigen::Vector3d& cells) {
  constexpr double kBytesPerTet = 1500.0, kBytesPerNode = 4000.0;
  const double nodes = (cells.x() + 1.0) * (cells.y() + 1.0) * (cells.z() + 1.0);
  const double tets = 5.0 * cells.x() * cells.y() * cells.z();  // five tets per lattice cell
  const double physical_bytes =
      static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGE_SIZE));
  const double needed_bytes = kBytesPerTet * tets + kBytesPerNode * nodes;
  const auto format = [](const char* pattern, double value) {
    char text[48];
    std::snprintf(text, sizeof(text), pattern, value);
    return std::string(text);
  };
  const auto gib = [&](double bytes) { return format("%.3g GiB", bytes / (1u << 30)); };
  if (nodes > 2147483647.0 || tets > 2147483647.0 || needed_bytes > physical_bytes)
    // Cell counts printed as %g: an ellipsoid's can exceed any integer type (5e30 m radii).
    map.FailKey(key, "a lattice of " + format("%.6g", cells.x()) + " x " +
                         format("%.6g", cells.y()) + " x " + format("%.6g", cells.z()) +
                         " cells (" + gib(needed_bytes) + " at least, " + format("%.3g", tets) +
                         " tets) does not fit in this machine's " + gib(physical_bytes) +
                         " of memory");
}

// `surface` with its cell size and optional refinement (MeshSource::Kind::kSurface).
void ReadSurfaceSource(const YamlMap& map, const std::string& base_dir, MeshSource* mesh) {
  mesh->kind = MeshSource::Kind::kSurface;
  mesh->file = ResolveSurfaceFile(map, "surface", base_dir);
  mesh->cell_size_m = map.GetDouble("cell_size_m", Above(0.0));
  if (const std::optional<YamlMap> refine = map.FindMap("refine")) {
    refine->CheckKeys({"near_m", "cell_size_m", "radius_m"});
    mesh->refine_near_m = refine->GetVector3("near_m");
    mesh->refine_cell_size_m = refine->GetDouble("cell_size_m", Above(0.0));
    if (mesh->refine_cell_size_m > mesh->cell_size_m)
      refine->FailKey("cell_size_m", "must not exceed the mesh's cell_size_m");
    mesh->refine_radius_m = refine->GetDouble("radius_m", Above(0.0));
  }
}

MeshSource ReadMesh(const YamlMap& map, const std::string& base_dir) {
  map.CheckKeys(
      {"box", "ellipsoid", "file", "surface", "cell_size_m", "refine", "units", "transform"});
  const int num_sources =
      map.Has("box") + map.Has("ellipsoid") + map.Has("file") + map.Has("surface");
  if (num_sources != 1) {
    map.Fail("must give exactly one of box, ellipsoid, file, surface; got " +
             std::to_string(num_sources));
  }
  for (const char* key : {"cell_size_m", "refine"})
    if (map.Has(key) && !map.Has("surface")) map.FailKey(key, "belongs to a surface mesh only");
  for (const char* key : {"units", "transform"})
    if (map.Has(key) && !map.Has("surface") && !map.Has("file"))
      map.FailKey(key, "belongs to a mesh file or surface (box and ellipsoid are in metres)");
  MeshSource mesh;
  mesh.location = LocationOf(map);
  mesh.transform = ReadMeshTransform(map);
  if (map.Has("surface")) {
    ReadSurfaceSource(map, base_dir, &mesh);
    return mesh;
  }
  if (const std::optional<YamlMap> box = map.FindMap("box")) {
    box->CheckKeys({"min_m", "max_m", "cells", "graded"});
    mesh.kind = MeshSource::Kind::kBox;
    mesh.box = ReadBox(*box, /*allow_flat=*/false);
    mesh.cells = box->GetVector3i("cells", AtLeast(1));
    CheckLatticeFitsMemory(*box, "cells", mesh.cells.cast<double>());
    if (const std::optional<YamlMap> graded = box->FindMap("graded")) {
      graded->CheckKeys({"focus_m", "ratio", "circle_radius_m"});
      mesh.grading_focus_m = graded->GetVector3("focus_m");
      mesh.grading_ratio = graded->GetDouble("ratio", AtLeast(1.0));
      if (graded->Has("circle_radius_m"))
        mesh.grading_circle_radius_m = graded->GetDouble("circle_radius_m", Above(0.0));
      const bool inside = (mesh.grading_focus_m.array() >= mesh.box.min_m.array()).all() &&
                          (mesh.grading_focus_m.array() <= mesh.box.max_m.array()).all();
      if (!inside) graded->FailKey("focus_m", "must lie inside the box (min_m to max_m)");
    }
  } else if (const std::optional<YamlMap> ellipsoid = map.FindMap("ellipsoid")) {
    ellipsoid->CheckKeys({"center_m", "radii_m", "cell_size_m"});
    mesh.kind = MeshSource::Kind::kEllipsoid;
    mesh.center_m = ellipsoid->GetVector3("center_m");
    mesh.radii_m = ellipsoid->GetVector3("radii_m", Above(0.0));
    mesh.cell_size_m = ellipsoid->GetDouble("cell_size_m", Above(0.0));
    // The cut lattice spans the bounding box of the ellipsoid.
    CheckLatticeFitsMemory(*ellipsoid, "cell_size_m",
                           (2.0 * mesh.radii_m / mesh.cell_size_m).array().ceil().matrix());
  } else {
    mesh.kind = MeshSource::Kind::kFile;
    mesh.file = ReadMeshFile(map, base_dir);
  }
  return mesh;
}

fem::Material ReadElasticMaterial(const YamlMap& map) {
  map.CheckKeys({"youngs_modulus_Pa", "poisson_ratio", "density_kg_m3", "rayleigh_alpha_1_s",
                 "rayleigh_beta_s"});
  fem::Material material;
  material.youngs_modulus_Pa = map.GetDouble("youngs_modulus_Pa", Above(0.0));
  material.poisson_ratio = map.GetDouble("poisson_ratio", OpenInterval(-1.0, 0.5));
  material.density_kg_m3 = map.GetDouble("density_kg_m3", Above(0.0));
  material.rayleigh_alpha_1_s = map.GetDoubleOr("rayleigh_alpha_1_s", 0.0, AtLeast(0.0));
  material.rayleigh_beta_s = map.GetDoubleOr("rayleigh_beta_s", 0.0, AtLeast(0.0));
  return material;
}

fem::SolverOptions ReadSolver(const YamlMap& map) {
  using fem::PreconditionerKind;
  using fem::SolverKind;
  map.CheckKeys({"type", "preconditioner", "relative_tolerance", "max_iterations",
                 "refactor_budget_iterations", "factor_precision"});
  fem::SolverOptions solver;
  solver.kind = map.GetEnumOr<SolverKind>(
      "type",
      {{ToString(SolverKind::kConjugateGradient), SolverKind::kConjugateGradient},
       {ToString(SolverKind::kCholmod), SolverKind::kCholmod}},
      solver.kind);
  solver.preconditioner = map.GetEnumOr<PreconditionerKind>(
      "preconditioner",
      {{ToString(PreconditionerKind::kLaggedCholesky), PreconditionerKind::kLaggedCholesky},
       {ToString(PreconditionerKind::kBlockJacobi), PreconditionerKind::kBlockJacobi}},
      solver.preconditioner);
  solver.refactor_budget_iterations =
      map.GetIntOr("refactor_budget_iterations", solver.refactor_budget_iterations, AtLeast(1));
  solver.factor_precision = map.GetEnumOr<fem::FactorPrecision>(
      "factor_precision",
      {{ToString(fem::FactorPrecision::kSingle), fem::FactorPrecision::kSingle},
       {ToString(fem::FactorPrecision::kDouble), fem::FactorPrecision::kDouble},
       {ToString(fem::FactorPrecision::kHalf), fem::FactorPrecision::kHalf}},
      solver.factor_precision);
  solver.relative_tolerance =
      map.GetDoubleOr("relative_tolerance", solver.relative_tolerance, OpenInterval(0.0, 1.0));
  solver.max_iterations = map.GetIntOr("max_iterations", solver.max_iterations, AtLeast(1));
  return solver;
}

fem::FemOptions ReadFemOptions(const YamlMap& body) {
  using fem::ElasticityKind;
  using fem::IntegratorKind;
  fem::FemOptions options;
  options.elasticity = body.GetEnumOr<ElasticityKind>(
      "elasticity",
      {{ToString(ElasticityKind::kCorotational), ElasticityKind::kCorotational},
       {ToString(ElasticityKind::kLinear), ElasticityKind::kLinear}},
      options.elasticity);
  options.integrator = body.GetEnumOr<IntegratorKind>(
      "integrator",
      {{ToString(IntegratorKind::kImplicitEuler), IntegratorKind::kImplicitEuler},
       {ToString(IntegratorKind::kExplicitEuler), IntegratorKind::kExplicitEuler}},
      options.integrator);
  if (const std::optional<YamlMap> solver = body.FindMap("solver")) {
    options.solver = ReadSolver(*solver);
  }
  return options;
}

NodalLoad ReadLoad(const YamlMap& map) {
  map.CheckKeys({"min_m", "max_m", "total_force_N"});
  NodalLoad load;
  load.region = ReadBox(map, /*allow_flat=*/true);
  load.total_force_N = map.GetVector3("total_force_N");
  load.location = LocationOf(map);
  return load;
}

std::vector<Probe> ReadProbes(const YamlMap& body) {
  std::vector<Probe> probes;
  for (const YamlMap& map : body.GetMapList("probes")) {
    map.CheckKeys({"name", "position_m"});
    Probe probe;
    probe.name = map.GetString("name");
    if (probe.name.empty()) map.FailKey("name", "must not be empty");
    for (const Probe& other : probes) {
      if (other.name == probe.name) {
        map.FailKey("name", "duplicate probe name '" + probe.name + "' (first given on line " +
                                std::to_string(other.location.line) + ")");
      }
    }
    probe.position_m = map.GetVector3("position_m");
    probe.location = LocationOf(map);
    probes.push_back(probe);
  }
  return probes;
}

BodyScene ReadBody(const YamlMap& map, const std::string& base_dir) {
  map.CheckKeys({"mesh", "element", "collision", "visual", "material", "elasticity", "integrator",
                 "solver", "fixed", "loads", "probes"});
  BodyScene body;
  body.mesh = ReadMesh(map.GetMap("mesh"), base_dir);
  body.quadratic = map.GetEnumOr<bool>("element", {{"p1", false}, {"p2", true}}, false);
  body.collision_surface = ReadEmbeddedSurface(map, "collision", base_dir);
  body.visual_surface = ReadEmbeddedSurface(map, "visual", base_dir);
  body.material = ReadElasticMaterial(map.GetMap("material"));
  body.options = ReadFemOptions(map);
  if (const std::optional<YamlMap> fixed = map.FindMap("fixed")) {
    fixed->CheckKeys({"min_m", "max_m"});
    body.fixed = ReadBox(*fixed, /*allow_flat=*/true);
    body.fixed_location = LocationOf(*fixed);
  }
  for (const YamlMap& load : map.GetMapList("loads")) body.loads.push_back(ReadLoad(load));
  body.probes = ReadProbes(map);
  return body;
}

// A deformable object after the first: it joins the first's FEM system (config/scene.h).
DeformableObjectScene ReadMoreBody(const YamlMap& map, const std::string& name,
                                   const BodyScene& first, const std::string& base_dir) {
  for (const char* key : {"elasticity", "integrator", "solver"}) {
    if (map.Has(key))
      map.FailKey(key,
                  "the deformable objects are solved as one system with the first one's FEM "
                  "options: give elasticity, integrator and solver there");
  }
  DeformableObjectScene more{name, ReadBody(map, base_dir), LocationOf(map)};
  more.body.options = first.options;
  if (more.body.material.rayleigh_alpha_1_s != first.material.rayleigh_alpha_1_s ||
      more.body.material.rayleigh_beta_s != first.material.rayleigh_beta_s)
    map.FailKey("material",
                "the deformable objects must share the first one's Rayleigh damping "
                "(rayleigh_alpha_1_s, rayleigh_beta_s): one damping serves the implicit step");
  return more;
}

// `objects`: names unique; the first deformable object (`body` counts, first) is scene.body.
void ReadObjects(const YamlMap& root, const std::string& base_dir, Scene* scene) {
  std::vector<std::pair<std::string, int>> names;  // name, line
  if (scene->body) names.emplace_back(scene->body_name, root.LineOf("body"));
  for (const YamlMap& item : root.GetMapList("objects")) {
    item.CheckKeys({"name", "deformable", "rigid"});
    const std::string name = item.GetString("name");
    if (name.empty()) item.FailKey("name", "must not be empty");
    for (const auto& [other, line] : names) {
      if (other == name)
        item.FailKey("name", "duplicate object name '" + name + "' (first given on line " +
                                 std::to_string(line) + ")");
    }
    names.emplace_back(name, item.LineOf("name"));
    if (item.Has("deformable") == item.Has("rigid"))
      item.Fail("must give exactly one of deformable, rigid");
    if (const std::optional<YamlMap> deformable = item.FindMap("deformable")) {
      if (scene->body) {
        scene->more_bodies.push_back(ReadMoreBody(*deformable, name, *scene->body, base_dir));
        // Probes report by name from the one merged body: names unique across the objects.
        std::vector<const Probe*> earlier;
        for (const Probe& probe : scene->body->probes) earlier.push_back(&probe);
        for (size_t k = 0; k + 1 < scene->more_bodies.size(); ++k)
          for (const Probe& probe : scene->more_bodies[k].body.probes) earlier.push_back(&probe);
        for (const Probe& probe : scene->more_bodies.back().body.probes)
          for (const Probe* other : earlier)
            if (other->name == probe.name)
              throw InputError(probe.location.file, probe.location.line,
                               probe.location.key + ".name",
                               "duplicate probe name '" + probe.name + "' (first given on line " +
                                   std::to_string(other->location.line) + ")");
      } else {
        scene->body = ReadBody(*deformable, base_dir);
        scene->body_name = name;
      }
    } else {
      scene->rigid_objects.push_back(ReadRigidObject(item.GetMap("rigid"), name, base_dir));
    }
  }
}

}  // namespace

Scene ParseScene(const std::string& yaml_text, const std::string& file_label,
                 const std::string& base_dir) {
  const YamlMap root = YamlMap::Parse(yaml_text, file_label);
  root.CheckKeys({"name", "description", "gravity_m_s2", "time", "body", "objects", "tool",
                  "coupling", "contact", "haptic", "device", "task"});
  Scene scene;
  scene.file = file_label;
  scene.name = root.GetString("name");
  if (scene.name.empty()) root.FailKey("name", "must not be empty");
  scene.description = root.GetStringOr("description", "");
  scene.gravity_m_s2 = root.GetVector3Or("gravity_m_s2", scene.gravity_m_s2);

  const YamlMap time = root.GetMap("time");
  time.CheckKeys({"dt_s", "num_steps"});
  scene.dt_s = time.GetDouble("dt_s", Above(0.0));
  scene.num_steps = time.GetInt("num_steps", AtLeast(1));

  if (const std::optional<YamlMap> body = root.FindMap("body")) {
    scene.body = ReadBody(*body, base_dir);
  }
  ReadObjects(root, base_dir, &scene);
  ReadSimulationSections(root, time, base_dir, &scene);
  if (!scene.tool && !scene.rigid_objects.empty())
    root.FailKey("objects",
                 "a rigid object needs a tool: its contacts are solved in the visual "
                 "frame (`hapsim sim`, `hapsim run`)");
  // One law serves every row of the response, rigid objects' included (DESIGN.md §9 wants those
  // unilateral): equality would glue a body resting on a support to it.
  if (!scene.rigid_objects.empty() && scene.contact.law == ContactLaw::kEquality)
    root.GetMap("contact").FailKey(
        "law",
        "equality holds bodies together, and a body resting on a rigid object could not "
        "lift off it: use unilateral or friction with rigid objects");
  for (const RigidObjectScene& rigid : scene.rigid_objects) {
    const SourceLocation& where = rigid.friction_location;
    if (rigid.object.friction_coefficient && scene.contact.law != ContactLaw::kFriction)
      throw InputError(where.file, where.line, where.key,
                       "an object's own friction coefficient needs contact.law: friction");
  }
  return scene;
}

Scene LoadScene(const std::string& path) {
  std::error_code error;
  if (!fs::exists(path, error)) throw InputError(path, 0, "", "no such scene file");
  if (fs::is_directory(path, error))
    throw InputError(path, 0, "", "is a directory, not a scene file");
  std::ifstream in(path, std::ios::binary);
  if (!in.is_open()) throw InputError(path, 0, "", "cannot open the scene file");
  std::ostringstream text;
  text << in.rdbuf();  // an empty file leaves `text` empty, which ParseScene reports
  if (in.bad()) throw InputError(path, 0, "", "cannot read the scene file");
  return ParseScene(text.str(), path, fs::path(path).parent_path().string());
}

}  // namespace hapsim::config
