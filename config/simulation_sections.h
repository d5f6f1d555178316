#pragma once
// Reading of the simulation sections of a scene file: tool, coupling, contact, haptic, device
// (schema in config/scene.h). Internal to the scene loader (config/scene.cc).

#include <optional>
#include <string>
#include <vector>

#include "config/scene.h"
#include "config/yaml_reader.h"
#include "core/mesh_transform.h"

namespace hapsim::config {

// Where `map` is in its file (file, line, key path), for the scene's errors and records.
SourceLocation LocationOf(const YamlMap& map);

// Reads tool, coupling, contact, haptic and device from the document root into *scene, with the
// checks between sections: everything but `tool` needs a tool; a tool needs coupling and device;
// haptic.rate_hz · time.dt_s must be a whole number ≥ 1 (`time` is the checked time section).
// Throws InputError naming file, line and key; errors in a tool mesh file name that file.
// A mesh file's `units: mm | cm | m` (default m) and `transform: {scale: s, rotation_vector_rad:
// [..], translation_m: [..]}` (s > 0, default 1; default no rotation or translation) in `mesh`,
// composed as core/mesh_transform.h says (the units' factor times s).
MeshTransform ReadMeshTransform(const YamlMap& mesh);

// The OBJ/STL file named by `key` of `map`, resolved against base_dir; fails at the key unless
// its extension is .obj or .stl (any case) and the file exists. For tool and object meshes and
// a body's `surface`.
std::string ResolveSurfaceFile(const YamlMap& map, const std::string& key,
                               const std::string& base_dir);

// A body's `collision` or `visual` entry, {file, units, transform}: a closed OBJ/STL surface its
// tets carry (fem/surface_embedding.h); nullopt when the key is absent.
std::optional<EmbeddedSurfaceSource> ReadEmbeddedSurface(const YamlMap& body,
                                                         const std::string& key,
                                                         const std::string& base_dir);

// One `rigid` entry of `objects` (config/scene.h), named `name`.
RigidObjectScene ReadRigidObject(const YamlMap& map, const std::string& name,
                                 const std::string& base_dir);

// The waypoint list `key` of `map` (≥ 1 waypoint, times ≥ 0 and strictly increasing): t_s,
// position_m, rotation_vector_rad (default 0) and, with_button, button (true | false, default
// false: the device button held from this waypoint to the next).
std::vector<Waypoint> ReadWaypoints(const YamlMap& map, const std::string& key, bool with_button);

void ReadSimulationSections(const YamlMap& root, const YamlMap& time, const std::string& base_dir,
                            Scene* scene);

}  // namespace hapsim::config
