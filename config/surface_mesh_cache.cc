#include "config/surface_mesh_cache.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <system_error>

#include "core/content_hash.h"
#include "core/error.h"
#include "core/tool_shape.h"
#include "core/triangle_mesh_io.h"
#include "fem/mesh_io.h"

namespace hapsim::config {
namespace fs = std::filesystem;
namespace {

// What the mesh depends on, as text: every option at full precision, and the mesher's version.
std::string DescribeOptions(const fem::SurfaceMeshOptions& options,
                            const MeshTransform& transform) {
  char line[256];
  std::string text = fem::SurfaceMesherVersion() + "\n";
  const Eigen::Vector3d& r = transform.rotation_vector_rad;
  const Eigen::Vector3d& t = transform.translation_m;
  std::snprintf(line, sizeof line, "transform %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n",
                transform.scale, r.x(), r.y(), r.z(), t.x(), t.y(), t.z());
  text += line;
  std::snprintf(line, sizeof line, "cell_size_m %.17g\n", options.cell_size_m);
  text += line;
  for (const Eigen::Vector3d& p : options.refine_near_m) {
    std::snprintf(line, sizeof line, "refine %.17g %.17g %.17g size %.17g radius %.17g\n", p.x(),
                  p.y(), p.z(), options.refine_cell_size_m, options.refine_radius_m);
    text += line;
  }
  return text;
}

}  // namespace

std::string SurfaceMeshCacheFolder() {
  if (const char* folder = std::getenv("HAPSIM_MESH_CACHE"); folder && *folder) return folder;
  if (const char* cache = std::getenv("XDG_CACHE_HOME"); cache && *cache)
    return (fs::path(cache) / "hapsim" / "meshes").string();
  if (const char* home = std::getenv("HOME"); home && *home)
    return (fs::path(home) / ".cache" / "hapsim" / "meshes").string();
  return "";
}

SurfaceMeshResult MeshSurfaceFile(const std::string& surface_file,
                                  const fem::SurfaceMeshOptions& options,
                                  const MeshTransform& transform) {
  TriangleMesh surface = ReadTriangleMesh(surface_file);  // checks closed and oriented
  transform.Apply(&surface.vertices_m);
  SurfaceMeshResult result;
  result.surface_volume_m3 = CalcSignedVolume_m3(surface);
  const std::string folder = SurfaceMeshCacheFolder();
  if (!folder.empty()) {
    const std::string key =
        Sha256Hex(DescribeOptions(options, transform) + Sha256OfFile(surface_file));
    result.cache_file = (fs::path(folder) / (key + ".msh")).string();
    std::error_code error;
    if (fs::is_regular_file(result.cache_file, error)) {
      try {
        result.mesh = fem::ReadGmshMesh(result.cache_file);
        result.from_cache = true;
        return result;
      } catch (const InputError& broken) {
        std::fprintf(stderr, "hapsim: note: meshing %s again: its cached mesh is unreadable (%s)\n",
                     surface_file.c_str(), broken.what());
      }
    }
  }
  result.mesh = fem::MeshClosedSurface(surface, options, surface_file);
  if (result.cache_file.empty()) return result;
  try {
    std::error_code error;
    fs::create_directories(fs::path(result.cache_file).parent_path(), error);
    if (error) throw InputError(folder, 0, "", error.message());
    fem::WriteGmshMesh(result.mesh, result.cache_file, 4);
  } catch (const InputError& unwritable) {
    std::fprintf(stderr, "hapsim: note: the mesh of %s is not cached: %s\n", surface_file.c_str(),
                 unwritable.what());
    result.cache_file.clear();
  }
  return result;
}

}  // namespace hapsim::config
