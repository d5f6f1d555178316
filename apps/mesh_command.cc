// `hapsim mesh SURFACE --cell-size-m H --out FILE`: a closed OBJ/STL surface filled with tets
// (fem/surface_mesher.h), as a scene's `mesh: {surface: ...}` does at load, written for other
// tools: Gmsh .msh (4.1, or 2.2 with --gmsh-version 2), TetGen .node/.ele, or legacy VTK .vtk
// (ParaView). Prints what a user judges a mesh by: tets, nodes, the extreme dihedral angles and
// the volume against the surface's. Uses and fills the same cache as the scenes
// (config/surface_mesh_cache.h). The output is written under a temporary name and renamed.

#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "config/surface_mesh_cache.h"
#include "core/error.h"
#include "core/mesh_transform.h"
#include "fem/mesh_io.h"
#include "fem/surface_mesher.h"

namespace hapsim::apps {
namespace {

struct MeshCommandOptions {
  std::string surface_path;
  std::string out_path;
  fem::SurfaceMeshOptions meshing;
  std::vector<double> refine_near_m;  // x y z, or empty
  int gmsh_version = 4;
  std::string units = "m";  // of the surface file
};

std::string LowerExtension(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

void WriteMesh(const fem::TetMesh& mesh, const MeshCommandOptions& options) {
  const std::string extension = LowerExtension(options.out_path);
  if (extension == ".msh") {
    fem::WriteGmshMesh(mesh, options.out_path, options.gmsh_version);
  } else if (extension == ".vtk") {
    fem::WriteVtkTetMesh(mesh.rest_positions_m, mesh.tets, {}, options.out_path);
  } else {  // .node: checked in RunMeshCommand
    fem::WriteTetgenMesh(mesh,
                         std::filesystem::path(options.out_path).replace_extension().string());
  }
}

void RunMeshCommand(MeshCommandOptions options) {
  const std::string extension = LowerExtension(options.out_path);
  if (extension != ".msh" && extension != ".vtk" && extension != ".node")
    throw InputError(options.out_path, 0, "--out",
                     "must end in .msh (Gmsh), .node (TetGen, with .ele) or .vtk (legacy VTK)");
  if (!options.refine_near_m.empty()) {
    options.meshing.refine_near_m = {Eigen::Vector3d(
        options.refine_near_m[0], options.refine_near_m[1], options.refine_near_m[2])};
    if (options.meshing.refine_cell_size_m == 0.0 || options.meshing.refine_radius_m == 0.0)
      throw InputError(options.surface_path, 0, "--refine-near",
                       "needs --refine-cell-size-m and --refine-radius-m too");
  }
  const auto start = std::chrono::steady_clock::now();
  MeshTransform transform;
  transform.scale = options.units == "mm" ? 0.001 : options.units == "cm" ? 0.01 : 1.0;
  const config::SurfaceMeshResult result =
      config::MeshSurfaceFile(options.surface_path, options.meshing, transform);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  WriteMesh(result.mesh, options);
  const fem::TetMeshQuality quality = fem::CalcTetMeshQuality(result.mesh);
  std::printf(
      "%s: %d tets, %d nodes, dihedral angles %.1f° to %.1f°, volume %.6g m³ (%+.2f %% of "
      "the surface's)\n",
      options.out_path.c_str(), quality.num_tets,
      static_cast<int>(result.mesh.rest_positions_m.cols()), quality.min_dihedral_deg,
      quality.max_dihedral_deg, quality.volume_m3,
      100.0 * (quality.volume_m3 / result.surface_volume_m3 - 1.0));
  std::printf("  %s in %.2f s%s%s\n", result.from_cache ? "read from the cache" : "meshed", seconds,
              result.cache_file.empty() ? "" : ": ", result.cache_file.c_str());
}

}  // namespace

void AddMeshCommand(CLI::App* app) {
  auto options = std::make_shared<MeshCommandOptions>();
  CLI::App* command = app->add_subcommand(
      "mesh",
      "Fills a closed OBJ/STL surface with tets (Gmsh), as a scene's `mesh: {surface: FILE, "
      "cell_size_m: H}` does at load, and writes them for other tools (.msh, .node/.ele, .vtk). "
      "Prints the tet count, the extreme dihedral angles and the volume against the surface's.");
  command->add_option("surface", options->surface_path, "Closed OBJ or STL surface")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("--cell-size-m", options->meshing.cell_size_m, "Edge length of the tets, m")
      ->required();
  command
      ->add_option("--out", options->out_path,
                   "Output: FILE.msh (Gmsh), FILE.node (TetGen, with FILE.ele) or FILE.vtk")
      ->required();
  command
      ->add_option("--units", options->units,
                   "Units of the surface file (m, cm or mm); the tets are written in metres")
      ->check(CLI::IsMember({"m", "cm", "mm"}))
      ->capture_default_str();
  command
      ->add_option("--gmsh-version", options->gmsh_version, "Gmsh file version, 4 (4.1) or 2 (2.2)")
      ->check(CLI::IsMember({2, 4}))
      ->capture_default_str();
  command
      ->add_option("--refine-near", options->refine_near_m,
                   "Finer cells near this point: X Y Z in metres")
      ->expected(3);
  command->add_option("--refine-cell-size-m", options->meshing.refine_cell_size_m,
                      "Edge length of the tets near --refine-near, m");
  command->add_option("--refine-radius-m", options->meshing.refine_radius_m,
                      "Within this distance of --refine-near the cells are finest; they grow to "
                      "--cell-size-m at twice it, m");
  command->callback([options] { RunMeshCommand(*options); });
}

}  // namespace hapsim::apps
