#pragma once
// What the scene tests (scene_test.cc, sim_scene_test.cc, the mesh-file ones) share: edit a
// scene's text, catch the InputError a bad scene throws and check that it names the file, line
// and key, and keep files (surfaces as OBJ text) in a temporary folder.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <ostream>
#include <sstream>
#include <string>

#include "config/scene.h"
#include "core/eigen_types.h"
#include "core/error.h"

namespace hapsim::config::test {

// `text` with its only occurrence of `find` replaced by `replace` (a failure if it is not there
// exactly once, so that a case cannot silently test the unchanged scene).
inline std::string Replace(std::string text, const std::string& find, const std::string& replace) {
  const std::size_t at = text.find(find);
  if (at == std::string::npos || text.find(find, at + 1) != std::string::npos) {
    ADD_FAILURE() << "'" << find << "' does not occur exactly once";
    return text;
  }
  return text.replace(at, find.size(), replace);
}

// The InputError that parsing `yaml` (as file `label`) throws, or nullopt if it parses.
inline std::optional<InputError> ParseError(const std::string& yaml, const std::string& label,
                                            const std::string& base_dir = "") {
  try {
    ParseScene(yaml, label, base_dir);
  } catch (const InputError& error) {
    return error;
  }
  return std::nullopt;
}

// Parsing `yaml` as `label` (its files resolved against base_dir) throws an InputError at `line`
// with `key`, whose message contains `message_part`.
inline void ExpectError(const std::string& yaml, const std::string& label, int line,
                        const std::string& key, const std::string& message_part,
                        const std::string& base_dir = "") {
  const std::optional<InputError> error = ParseError(yaml, label, base_dir);
  ASSERT_TRUE(error.has_value()) << "parsed without error:\n" << yaml;
  EXPECT_EQ(error->file(), label);
  EXPECT_EQ(error->line(), line) << error->what();
  EXPECT_EQ(error->key(), key) << error->what();
  EXPECT_NE(std::string(error->what()).find(message_part), std::string::npos) << error->what();
}

// A one-body scene whose `mesh:` (on line 4) is `mesh` throws an InputError at line 4 with `key`,
// whose message contains `message_part` (ExpectError); the mesh's files resolve in base_dir.
inline void ExpectBodyMeshError(const std::string& mesh, const std::string& key,
                                const std::string& message_part, const std::string& base_dir) {
  ExpectError("name: t\ntime: {dt_s: 0.01, num_steps: 1}\nbody:\n  mesh: " + mesh +
                  "\n  material: {youngs_modulus_Pa: 1, poisson_ratio: 0.3, density_kg_m3: 1}\n",
              "t.yaml", 4, key, message_part, base_dir);
}

// One kind of bad input: a scene with `find` replaced by `replace` must throw InputError at
// `line` with `key`, and its message must contain `message_part`.
struct BadCase {
  const char* name;
  const char* find;
  const char* replace;
  int line;
  const char* key;
  const char* message_part;
};

inline std::ostream& operator<<(std::ostream& out, const BadCase& c) { return out << c.name; }

// A closed surface as Wavefront OBJ text, coordinates to 17 digits (read back exactly).
inline std::string ObjText(const Matrix3Xd& vertices_m, const Matrix3Xi& triangles) {
  std::ostringstream out;
  out.precision(17);
  for (Eigen::Index v = 0; v < vertices_m.cols(); ++v)
    out << "v " << vertices_m(0, v) << ' ' << vertices_m(1, v) << ' ' << vertices_m(2, v) << '\n';
  for (Eigen::Index t = 0; t < triangles.cols(); ++t)
    out << "f " << triangles(0, t) + 1 << ' ' << triangles(1, t) + 1 << ' ' << triangles(2, t) + 1
        << '\n';
  return out.str();
}

// A folder under the test temp dir; removed on destruction.
class TempFolder {
 public:
  explicit TempFolder(const std::string& name)
      : path_(std::filesystem::path(testing::TempDir()) / ("hapsim_scene_test_" + name)) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempFolder() { std::filesystem::remove_all(path_); }
  // Writes `text` to the file `name` in the folder; returns its path.
  std::string Write(const std::string& name, const std::string& text = "") const {
    std::ofstream(path_ / name) << text;
    return (path_ / name).string();
  }
  std::string path() const { return path_.string(); }

 private:
  std::filesystem::path path_;
};

}  // namespace hapsim::config::test
