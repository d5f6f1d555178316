#include "apps/run_info.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "core/content_hash.h"
#include "core/error.h"
#include "core/realtime.h"

namespace hapsim::apps {
namespace fs = std::filesystem;

std::vector<std::string> SceneInputFiles(const config::Scene& scene) {
  std::vector<std::string> files;
  std::vector<const config::BodyScene*> bodies;
  if (scene.body) bodies.push_back(&*scene.body);
  for (const config::DeformableObjectScene& more : scene.more_bodies) bodies.push_back(&more.body);
  for (const config::BodyScene* body : bodies) {
    if (body->mesh.kind == config::MeshSource::Kind::kSurface) {  // meshed at load: its surface
      files.push_back(fs::absolute(body->mesh.file).lexically_normal().string());
      continue;
    }
    if (body->mesh.kind != config::MeshSource::Kind::kFile) continue;
    const fs::path mesh = fs::absolute(body->mesh.file);
    std::string extension = mesh.extension().string();
    for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (extension == ".msh") {
      files.push_back(mesh.lexically_normal().string());
    } else {  // TetGen: the .node / .ele pair, whichever of the three forms the scene named
      fs::path base = mesh;
      if (extension == ".node" || extension == ".ele") base.replace_extension();
      for (const char* suffix : {".node", ".ele"})
        files.push_back(fs::path(base.string() + suffix).lexically_normal().string());
    }
  }
  if (scene.tool && !scene.tool->mesh_file.empty())
    files.push_back(fs::absolute(scene.tool->mesh_file).lexically_normal().string());
  for (const config::RigidObjectScene& rigid : scene.rigid_objects) {
    if (!rigid.mesh_file.empty())
      files.push_back(fs::absolute(rigid.mesh_file).lexically_normal().string());
  }
  // Objects may share a file: each is listed (and hashed) once, in first-use order.
  std::vector<std::string> unique;
  for (const std::string& file : files)
    if (std::find(unique.begin(), unique.end(), file) == unique.end()) unique.push_back(file);
  return unique;
}

hapsim_lcm::run_info_t MakeRunInfo(const config::Scene& scene, const std::string& mode,
                                   std::int64_t run_id) {
  hapsim_lcm::run_info_t info{};
  info.utime = WallMicros();
  info.run_id = run_id;
  info.scene_path = scene.file;
  std::ifstream in(scene.file, std::ios::binary);
  info.scene_yaml.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (!in) throw InputError(scene.file, 0, "", "cannot read the scene file again for RUN_INFO");
  info.scene_directory = fs::absolute(scene.file).parent_path().lexically_normal().string();
  for (const std::string& file : SceneInputFiles(scene)) {
    info.file_paths.push_back(file);
    info.file_sha256.push_back(Sha256OfFile(file));
  }
  info.num_files = static_cast<std::int32_t>(info.file_paths.size());
  info.mode = mode;
  info.visual_rate_hz = 1.0 / scene.dt_s;
  info.haptic_rate_hz = scene.haptic.rate_hz;
  info.hapsim_version = HAPSIM_VERSION;
  return info;
}

config::Scene LoadLoggedScene(const hapsim_lcm::run_info_t& info, const std::string& log_path) {
  for (int i = 0; i < info.num_files; ++i) {
    const std::string& file = info.file_paths[i];
    std::error_code error;
    if (!fs::is_regular_file(file, error))
      throw InputError(file, 0, "",
                       "the logged scene reads this file, which is missing (log " + log_path +
                           "; give --scene to replay with another scene)");
    if (Sha256OfFile(file) != info.file_sha256[i])
      throw InputError(file, 0, "",
                       "changed since the run: its SHA-256 is not the one recorded in " + log_path +
                           " (" + info.file_sha256[i] + "); give --scene to replay anyway");
  }
  const std::string label = log_path + " (RUN_INFO scene_yaml of " + info.scene_path + ")";
  return config::ParseScene(info.scene_yaml, label, info.scene_directory);
}

}  // namespace hapsim::apps
