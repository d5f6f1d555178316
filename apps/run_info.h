#pragma once
// RUN_INFO (messages/run_info_t.lcm): what makes a log self-contained (issue 9). The visual
// process records the scene's text, its folder, and every file the scene reads with its SHA-256;
// replay parses the logged text, not today's scene file, after checking that each file is still
// there with the same content, so it works from any folder and refuses a changed input.
//
// The files travel as hashes, not as content: a body mesh of 28,800 tets is ~2 MB of text that
// RUN_INFO would carry over UDP at every announcement, while a hash lets replay name the file
// that changed. (A log moved to another machine needs the mesh files at the same absolute paths.)

#include <cstdint>
#include <string>
#include <vector>

#include "config/scene.h"
#include "messages/adapters.h"

namespace hapsim::apps {

// The files `scene` reads, as resolved when it was loaded: the body mesh (a TetGen mesh's .node
// and .ele) and the tool mesh. Absolute paths.
std::vector<std::string> SceneInputFiles(const config::Scene& scene);

// RUN_INFO for a run of `scene` (loaded from scene.file) in `mode`. Reads the scene file's text and
// hashes each input file; throws InputError naming a file it cannot read.
hapsim_lcm::run_info_t MakeRunInfo(const config::Scene& scene, const std::string& mode,
                                   std::int64_t run_id);

// The scene of a logged run: every file in info is checked (missing, or content changed since
// the run: an InputError naming the file and the log), then info.scene_yaml is parsed with
// relative paths resolved against info.scene_directory. Errors in the text name the log.
config::Scene LoadLoggedScene(const hapsim_lcm::run_info_t& info, const std::string& log_path);

}  // namespace hapsim::apps
