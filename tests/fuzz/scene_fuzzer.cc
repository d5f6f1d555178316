// Fuzz target: the scene reader (config::ParseScene) on YAML text, then what a run does next with
// a scene it accepts: the body (config::MakeBody, when its lattice is small enough to build in
// milliseconds) and the options of the simulation sections.
//
// Relative mesh paths resolve against the scratch folder, which holds a closed tool mesh
// (tool.obj, tool.stl) and a two-tet body mesh (body.msh, body.node + body.ele), so that seeds can
// name them; the readers themselves are fuzzed by their own targets.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string>
#include <vector>

#include "config/body_builder.h"
#include "config/scene.h"
#include "config/simulation_builder.h"
#include "contact/rigid_objects.h"
#include "tests/fuzz/fuzz_support.h"

namespace {

using namespace hapsim;

// A lattice above this many cells is not built: meshing and the model grow with it (a few ms
// at this size), and scenes that ask for more memory than the machine has are ParseScene's to
// refuse, not MakeBody's to try.
constexpr double kMaxBuiltCells = 2000;

constexpr char kToolObj[] = R"(# unit cube, outward
v 0 0 0
v 1 0 0
v 0 1 0
v 1 1 0
v 0 0 1
v 1 0 1
v 0 1 1
v 1 1 1
f 1 3 4 2
f 5 6 8 7
f 1 2 6 5
f 3 7 8 4
f 1 5 7 3
f 2 4 8 6
)";

constexpr char kToolStl[] = R"(solid tet
facet normal 0 0 -1
outer loop
vertex 0 0 0
vertex 0 1 0
vertex 1 0 0
endloop
endfacet
facet normal 0 -1 0
outer loop
vertex 0 0 0
vertex 1 0 0
vertex 0 0 1
endloop
endfacet
facet normal -1 0 0
outer loop
vertex 0 0 0
vertex 0 0 1
vertex 0 1 0
endloop
endfacet
facet normal 1 1 1
outer loop
vertex 1 0 0
vertex 0 1 0
vertex 0 0 1
endloop
endfacet
endsolid tet
)";

constexpr char kBodyMsh[] = R"($MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
5
1 0 0 0
2 1 0 0
3 0 1 0
4 0 0 1
5 0 0 -1
$EndNodes
$Elements
2
1 4 2 7 1 1 2 3 4
2 4 2 7 1 1 3 2 5
$EndElements
)";

constexpr char kBodyNode[] = "5 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 0 0 -1\n";
constexpr char kBodyEle[] = "2 4 0\n1 1 2 3 4\n2 1 3 2 5\n";

void WriteText(const char* name, const std::string& text) {
  fuzz::WriteScratchFile(name, reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
}

bool SmallEnoughToBuild(const config::MeshSource& mesh) {
  switch (mesh.kind) {
    case config::MeshSource::Kind::kBox:
      return static_cast<double>(mesh.cells.x()) * mesh.cells.y() * mesh.cells.z() <=
             kMaxBuiltCells;
    case config::MeshSource::Kind::kEllipsoid: {
      // config/body_builder.cc's lattice: 2 ceil(1.05 r / h) cells per axis.
      double cells = 1.0;
      for (int axis = 0; axis < 3; ++axis)
        cells *= 2.0 * std::ceil(1.05 * mesh.radii_m[axis] / mesh.cell_size_m);
      return cells <= kMaxBuiltCells;
    }
    case config::MeshSource::Kind::kFile:
      return true;  // the files above, or whatever else a seed names: the readers bound them
    case config::MeshSource::Kind::kSurface:
      return false;  // a Gmsh run in a child process per input: the surface_mesher target's
  }
  return false;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool files_written = [] {
    WriteText("tool.obj", kToolObj);
    WriteText("tool.stl", kToolStl);
    WriteText("body.msh", kBodyMsh);
    WriteText("body.node", kBodyNode);
    WriteText("body.ele", kBodyEle);
    return true;
  }();
  (void)files_written;

  const std::string text(reinterpret_cast<const char*>(data), size);
  config::Scene scene;
  if (!fuzz::RunReader([&] { scene = config::ParseScene(text, "fuzz.yaml", fuzz::ScratchDir()); }))
    return 0;
  fuzz::CheckOrDie(std::isfinite(scene.dt_s) && scene.dt_s > 0.0 && scene.num_steps >= 1,
                   "ParseScene accepted dt_s " + std::to_string(scene.dt_s) + ", num_steps " +
                       std::to_string(scene.num_steps));
  if (scene.body && SmallEnoughToBuild(scene.body->mesh)) {
    fuzz::RunReader([&] { config::MakeBody(*scene.body, scene.gravity_m_s2); });
  }
  if (scene.tool) {
    fuzz::CheckOrDie(scene.haptic.steps_per_frame >= 1,
                     "ParseScene accepted a tool with steps_per_frame " +
                         std::to_string(scene.haptic.steps_per_frame));
    fuzz::RunReader([&] {
      config::MakeVisualFrameOptions(scene);
      const device::HapticMode mode = config::ResolveHapticMode(scene, "", "--mode", true);
      config::MakeMultirateOptions(scene, mode, scene.haptic.steps_per_frame);
    });
    // Rigid objects: the parser checked each shape's distance field, so the contact stage must
    // take them all (with the tool) without an exception, and their boxes must be finite.
    std::vector<contact::RigidObject> objects;
    for (const config::RigidObjectScene& rigid : scene.rigid_objects) {
      objects.push_back(rigid.object);
      const Eigen::AlignedBox3d box = contact::CalcWorldBox(rigid.object);
      fuzz::CheckOrDie(box.min().allFinite() && box.max().allFinite(),
                       "ParseScene accepted a rigid object with a non-finite extent");
    }
    try {
      contact::RigidObjectContacts contacts(objects, scene.tool->model.shape,
                                            scene.contact.margin_m);
    } catch (const std::exception& error) {
      fuzz::CheckOrDie(false, std::string("ParseScene accepted rigid objects the contact stage "
                                          "refuses: ") +
                                  error.what());
    }
  }
  return 0;
}
