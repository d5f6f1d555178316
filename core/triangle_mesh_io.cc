#include "core/triangle_mesh_io.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"

namespace hapsim {
namespace {

// Triangles as read, each with where it came from (a line for text formats, else 0).
struct MeshBuilder {
  std::vector<Eigen::Vector3d> vertices_m;
  std::vector<Eigen::Vector3i> triangles;
  std::vector<int> triangle_line;
  bool binary = false;  // an offending triangle is then named by key "triangle N", line 0
};

std::string Lowercase(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::vector<std::string> SplitWhitespace(const std::string& line) {
  std::istringstream stream(line);
  return {std::istream_iterator<std::string>(stream), std::istream_iterator<std::string>()};
}

// A tool's volume and inertia integrals grow as the third and fifth power of its size: a vertex
// at 1e308 m made them infinite (found by fuzzing). A kilometre is far beyond any tool, and beyond
// a millimetres-for-metres slip in a file's units.
constexpr double kMaxCoordinate_m = 1e3;

double ParseCoordinate(const std::string& token, const std::string& path, int line) {
  char* end = nullptr;
  const double value = std::strtod(token.c_str(), &end);
  if (end == token.c_str() || *end != '\0' || !std::isfinite(value)) {
    throw InputError(path, line, "", "'" + token + "' is not a finite number");
  }
  if (std::abs(value) > kMaxCoordinate_m) {
    throw InputError(path, line, "",
                     "coordinate " + token + " is beyond 1000 m (units are metres)");
  }
  return value;
}

Eigen::Vector3d ParsePoint(const std::vector<std::string>& tokens, size_t first,
                           const std::string& path, int line) {
  if (tokens.size() < first + 3) {
    throw InputError(path, line, "", "'" + tokens[0] + "' needs three coordinates");
  }
  return {ParseCoordinate(tokens[first], path, line),
          ParseCoordinate(tokens[first + 1], path, line),
          ParseCoordinate(tokens[first + 2], path, line)};
}

// One OBJ face corner "i", "i/t", "i//n" or "i/t/n" → 0-based vertex index.
int ParseObjIndex(const std::string& token, int num_vertices, const std::string& path, int line) {
  const std::string index_text = token.substr(0, token.find('/'));
  char* end = nullptr;
  const long index = std::strtol(index_text.c_str(), &end, 10);
  if (index_text.empty() || *end != '\0') {
    throw InputError(path, line, "", "face vertex '" + token + "' is not an index");
  }
  // Positive: 1-based absolute; negative: relative to the end of the vertices read so far.
  const long resolved = index > 0 ? index - 1 : num_vertices + index;
  if (index == 0 || resolved < 0 || resolved >= num_vertices) {
    throw InputError(path, line, "",
                     "face vertex index " + std::to_string(index) + " does not name one of the " +
                         std::to_string(num_vertices) + " vertices defined so far");
  }
  return static_cast<int>(resolved);
}

MeshBuilder ReadObj(std::istream& in, const std::string& path) {
  MeshBuilder mesh;
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    const std::vector<std::string> tokens = SplitWhitespace(text);
    if (tokens.empty()) continue;
    if (tokens[0] == "v") {
      mesh.vertices_m.push_back(ParsePoint(tokens, 1, path, line));
    } else if (tokens[0] == "f") {
      if (tokens.size() < 4) throw InputError(path, line, "", "a face needs at least 3 vertices");
      const int n = static_cast<int>(mesh.vertices_m.size());
      std::vector<int> corners;
      for (size_t k = 1; k < tokens.size(); ++k) {
        corners.push_back(ParseObjIndex(tokens[k], n, path, line));
      }
      for (size_t k = 1; k + 1 < corners.size(); ++k) {  // fan: (0, k, k + 1)
        mesh.triangles.emplace_back(corners[0], corners[k], corners[k + 1]);
        mesh.triangle_line.push_back(line);
      }
    }
  }
  return mesh;
}

// Index of a vertex with exactly these coordinates, adding it if new.
int AddMergedVertex(const Eigen::Vector3d& p, std::map<std::array<double, 3>, int>* index,
                    MeshBuilder* mesh) {
  const auto [it, inserted] =
      index->emplace(std::array<double, 3>{p.x(), p.y(), p.z()}, mesh->vertices_m.size());
  if (inserted) mesh->vertices_m.push_back(p);
  return it->second;
}

// ASCII STL as a small state machine over keyword lines.
MeshBuilder ReadStlAscii(std::istream& in, const std::string& path) {
  enum class Expect { kSolid, kFacetOrEnd, kOuterLoop, kVertex, kEndFacet, kSolidOrEof };
  MeshBuilder mesh;
  std::map<std::array<double, 3>, int> index;
  Expect expect = Expect::kSolid;
  std::array<int, 3> corners{};
  int num_corners = 0, facet_line = 0, line = 0;
  std::string text;
  auto fail = [&](const std::string& message) -> InputError {
    return InputError(path, line, "", message);
  };
  while (std::getline(in, text)) {
    ++line;
    const std::vector<std::string> tokens = SplitWhitespace(text);
    if (tokens.empty()) continue;
    const std::string keyword = Lowercase(tokens[0]);
    if (keyword == "solid" && (expect == Expect::kSolid || expect == Expect::kSolidOrEof)) {
      expect = Expect::kFacetOrEnd;
    } else if (keyword == "facet" && expect == Expect::kFacetOrEnd) {
      expect = Expect::kOuterLoop;
      facet_line = line;
    } else if (keyword == "endsolid" && expect == Expect::kFacetOrEnd) {
      expect = Expect::kSolidOrEof;
    } else if (keyword == "outer" && expect == Expect::kOuterLoop) {
      expect = Expect::kVertex;
      num_corners = 0;
    } else if (keyword == "vertex" && expect == Expect::kVertex) {
      if (num_corners == 3) throw fail("a facet has more than 3 vertices");
      corners[num_corners++] = AddMergedVertex(ParsePoint(tokens, 1, path, line), &index, &mesh);
    } else if (keyword == "endloop" && expect == Expect::kVertex) {
      if (num_corners != 3) throw fail("a facet needs exactly 3 vertices");
      mesh.triangles.emplace_back(corners[0], corners[1], corners[2]);
      mesh.triangle_line.push_back(facet_line);
      expect = Expect::kEndFacet;
    } else if (keyword == "endfacet" && expect == Expect::kEndFacet) {
      expect = Expect::kFacetOrEnd;
    } else {
      throw fail("unexpected '" + tokens[0] + "'");
    }
  }
  if (expect != Expect::kSolidOrEof) {
    throw fail(expect == Expect::kSolid ? "no 'solid' found" : "the file ends inside a solid");
  }
  return mesh;
}

float ReadFloat(const char* bytes) {
  float value;
  std::memcpy(&value, bytes, sizeof value);
  return value;
}

// Binary STL: 80-byte header, uint32 n, n × (normal, 3 vertices: 12 floats; uint16 attribute).
MeshBuilder ReadStlBinary(const std::string& bytes, uint32_t num_triangles,
                          const std::string& path) {
  MeshBuilder mesh;
  mesh.binary = true;
  std::map<std::array<double, 3>, int> index;
  for (uint32_t t = 0; t < num_triangles; ++t) {
    const char* facet = bytes.data() + 84 + 50 * static_cast<size_t>(t);
    Eigen::Vector3i corners;
    for (int k = 0; k < 3; ++k) {
      const char* p = facet + 12 + 12 * k;
      const Eigen::Vector3d point(ReadFloat(p), ReadFloat(p + 4), ReadFloat(p + 8));
      if (!point.allFinite()) {
        throw InputError(path, 0, "triangle " + std::to_string(t), "non-finite vertex coordinate");
      }
      if (point.cwiseAbs().maxCoeff() > kMaxCoordinate_m) {
        throw InputError(path, 0, "triangle " + std::to_string(t),
                         "a vertex coordinate is beyond 1000 m (units are metres)");
      }
      corners[k] = AddMergedVertex(point, &index, &mesh);
    }
    mesh.triangles.push_back(corners);
    mesh.triangle_line.push_back(0);
  }
  return mesh;
}

MeshBuilder ReadStl(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "", "cannot open file");
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.size() >= 84) {
    uint32_t num_triangles;
    std::memcpy(&num_triangles, bytes.data() + 80, sizeof num_triangles);
    if (bytes.size() == 84 + 50 * static_cast<uint64_t>(num_triangles)) {
      return ReadStlBinary(bytes, num_triangles, path);
    }
  }
  std::istringstream text(bytes);
  return ReadStlAscii(text, path);
}

// Closedness, orientation and volume; flips an inward mesh.
TriangleMesh Finish(const MeshBuilder& built, const std::string& path) {
  const bool binary = built.binary;
  TriangleMesh mesh;
  mesh.vertices_m.resize(3, static_cast<Eigen::Index>(built.vertices_m.size()));
  for (size_t i = 0; i < built.vertices_m.size(); ++i) mesh.vertices_m.col(i) = built.vertices_m[i];
  mesh.triangles.resize(3, static_cast<Eigen::Index>(built.triangles.size()));
  for (size_t f = 0; f < built.triangles.size(); ++f) mesh.triangles.col(f) = built.triangles[f];
  std::string defect;
  const int bad = FindOpenOrMisorientedTriangle(mesh, &defect);
  if (bad >= 0) {
    const bool known = bad < static_cast<int>(built.triangle_line.size());
    const int line = known && !binary ? built.triangle_line[bad] : 0;
    throw InputError(path, line, binary ? "triangle " + std::to_string(bad) : "", defect);
  }
  const double volume_m3 = CalcSignedVolume_m3(mesh);
  const Eigen::Vector3d size_m =
      mesh.vertices_m.rowwise().maxCoeff() - mesh.vertices_m.rowwise().minCoeff();
  // Relative to the bounding box: only rounding is left of a flat (doubled-sheet) mesh.
  constexpr double kFlatVolumeFraction = 1e-12;
  if (!(std::abs(volume_m3) > kFlatVolumeFraction * size_m.prod())) {
    throw InputError(path, 0, "", "the mesh encloses no volume");
  }
  if (volume_m3 < 0.0) mesh.triangles.row(1).swap(mesh.triangles.row(2));  // all faces inward
  return mesh;
}

}  // namespace

TriangleMesh ReadTriangleMesh(const std::string& path) {
  const size_t dot = path.find_last_of('.');
  const std::string extension = dot == std::string::npos ? "" : Lowercase(path.substr(dot));
  if (extension == ".obj") {
    std::ifstream in(path);
    if (!in) throw InputError(path, 0, "", "cannot open file");
    return Finish(ReadObj(in, path), path);
  }
  if (extension == ".stl") {
    return Finish(ReadStl(path), path);
  }
  throw InputError(path, 0, "", "unknown mesh format '" + extension + "' (expected .obj or .stl)");
}

}  // namespace hapsim
