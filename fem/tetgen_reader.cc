// TetGen .node/.ele reader and the ReadTetMesh dispatch.

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>
#include <unordered_map>

#include "core/error.h"
#include "fem/mesh_io.h"
#include "fem/mesh_text_reader.h"

namespace hapsim::fem {

namespace {

using internal::MeshTextReader;
using internal::RawNode;
using internal::RawTet;

// Parses a count: a non-negative integer that fits an int.
int ParseCount(const MeshTextReader& reader, const std::string& token, const std::string& key) {
  const long long value = reader.ParseInteger(token, key, key);
  if (value < 0 || value > std::numeric_limits<int>::max())
    reader.Fail(key, key + " must be between 0 and 2^31-1, found " + token);
  return static_cast<int>(value);
}

// Reads the header line of a .node/.ele file: up to names.size() integers (missing trailing ones
// keep TetGen's defaults, given in `values`). Throws if the file is empty or the header is
// malformed.
void ReadTetgenHeader(MeshTextReader* reader, const std::string& layout,
                      const std::vector<std::string>& names, std::vector<int>* values) {
  std::vector<std::string> tokens;
  if (!reader->NextTokens(&tokens, true))
    reader->Fail("header", "the file is empty; expected the header '" + layout + "'");
  if (tokens.size() > names.size())
    reader->Fail("header", "expected the header '" + layout + "', found " +
                               std::to_string(tokens.size()) + " values");
  for (size_t i = 0; i < tokens.size(); ++i)
    (*values)[i] = ParseCount(*reader, tokens[i], names[i]);
}

// Reads the `count` entry lines after a header on line `header_line`, each with
// `num_tokens` values, calling parse(tokens, i) for each; then checks that no entries follow.
template <typename ParseEntry>
void ReadTetgenEntries(MeshTextReader* reader, int count, int header_line, size_t num_tokens,
                       const std::string& entry, const std::string& layout, ParseEntry parse) {
  std::vector<std::string> tokens;
  const std::string declared = " declared on line " + std::to_string(header_line);
  for (int i = 0; i < count; ++i) {
    if (!reader->NextTokens(&tokens, true))
      reader->Fail(entry + " count", "unexpected end of file: expected " + entry + " " +
                                         std::to_string(i + 1) + " of the " +
                                         std::to_string(count) + declared);
    if (tokens.size() != num_tokens)
      reader->Fail(entry, "expected " + std::to_string(num_tokens) + " values (" + layout +
                              "), found " + std::to_string(tokens.size()));
    parse(tokens, i);
  }
  if (reader->NextTokens(&tokens, true))
    reader->Fail(entry + " count",
                 "more " + entry + "s than the " + std::to_string(count) + declared);
}

// Reads a .node file. Tags are the file's indices, which must be consecutive from 0 or 1.
std::vector<RawNode> ReadTetgenNodes(const std::string& path) {
  MeshTextReader reader(path);
  std::vector<int> header = {0, 3, 0, 0};
  ReadTetgenHeader(&reader, "<# of points> <dimension> <# of attributes> <boundary markers>",
                   {"point count", "dimension", "attribute count", "boundary markers"}, &header);
  const int header_line = reader.line_number();
  const int count = header[0], dimension = header[1];
  const int num_attributes = header[2], num_markers = header[3];
  if (dimension != 3) reader.Fail("dimension", "must be 3, found " + std::to_string(dimension));
  if (num_markers > 1) reader.Fail("boundary markers", "must be 0 or 1");
  if (count == 0) reader.Fail("point count", "the mesh has no points");
  std::vector<RawNode> nodes;  // grown entry by entry: a bogus count must not allocate
  const std::string layout = "index, x, y, z, " + std::to_string(num_attributes) +
                             " attribute(s), " + std::to_string(num_markers) + " marker(s)";
  // Counts are summed as size_t: 4 + 2^31-1 attributes overflowed int (found by fuzzing).
  ReadTetgenEntries(
      &reader, count, header_line, size_t{4} + num_attributes + num_markers, "point", layout,
      [&](const std::vector<std::string>& tokens, int i) {
        const long long index = reader.ParseInteger(tokens[0], "point", "the point index");
        const long long first = i == 0 ? index : nodes[0].tag;
        if (i == 0 && index != 0 && index != 1)
          reader.Fail("point", "point numbering must start at 0 or 1, found " + tokens[0]);
        if (index != first + i)
          reader.Fail("point", "points must be numbered consecutively: expected " +
                                   std::to_string(first + i) + ", found " + tokens[0]);
        Eigen::Vector3d p_m;
        for (int k = 0; k < 3; ++k)
          p_m[k] = reader.ParseReal(tokens[1 + k], "point",
                                    std::string("the ") + "xyz"[k] + " coordinate");
        for (size_t k = 4; k < tokens.size(); ++k)
          reader.ParseReal(tokens[k], "point", "an attribute or marker");
        nodes.push_back({index, p_m, reader.line_number()});
      });
  return nodes;
}

// Reads a .ele file of 4-node tets; node references are checked later against the .node tags.
std::vector<RawTet> ReadTetgenTets(const std::string& path) {
  MeshTextReader reader(path);
  std::vector<int> header = {0, 4, 0};
  ReadTetgenHeader(&reader, "<# of tetrahedra> <nodes per tetrahedron> <region attribute>",
                   {"tetrahedron count", "nodes per tetrahedron", "region attribute"}, &header);
  const int header_line = reader.line_number();
  const int count = header[0], nodes_per_tet = header[1], num_attributes = header[2];
  if (nodes_per_tet == 10)
    reader.Fail("nodes per tetrahedron",
                "10-node (second-order, tetgen -o2) tetrahedra are not supported; "
                "hapsim needs linear 4-node tetrahedra");
  if (nodes_per_tet != 4)
    reader.Fail("nodes per tetrahedron", "must be 4, found " + std::to_string(nodes_per_tet));
  if (count == 0) reader.Fail("tetrahedron count", "the mesh has no tetrahedra");
  std::vector<RawTet> tets;  // grown entry by entry: a bogus count must not allocate
  const std::string layout = "index, 4 nodes, " + std::to_string(num_attributes) + " attribute(s)";
  ReadTetgenEntries(
      &reader, count, header_line, size_t{5} + num_attributes, "tetrahedron", layout,
      [&](const std::vector<std::string>& tokens, int /*i*/) {
        RawTet tet{
            reader.ParseInteger(tokens[0], "tetrahedron", "the index"), {}, reader.line_number()};
        for (int a = 0; a < 4; ++a)
          tet.nodes[a] = reader.ParseInteger(tokens[1 + a], "tetrahedron", "a node index");
        for (size_t k = 5; k < tokens.size(); ++k)
          reader.ParseReal(tokens[k], "tetrahedron", "the region attribute");
        tets.push_back(tet);
      });
  return tets;
}

// Lower-case extension of `path` including the dot ("" if none).
std::string LowerExtension(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

}  // namespace

TetMesh ReadTetgenMesh(const std::string& node_path) {
  const std::string extension = LowerExtension(node_path);
  std::string basename = node_path;
  if (extension == ".node" || extension == ".ele")
    basename.resize(node_path.size() - extension.size());
  const std::string node_file = basename + ".node";
  const std::string ele_file = basename + ".ele";
  const std::vector<RawNode> nodes = ReadTetgenNodes(node_file);
  const std::vector<RawTet> tets = ReadTetgenTets(ele_file);
  return internal::MakeCheckedTetMesh(nodes, node_file, "point", tets, ele_file, "tetrahedron");
}

TetMesh ReadTetMesh(const std::string& path) {
  const std::string extension = LowerExtension(path);
  if (extension == ".msh") return ReadGmshMesh(path);
  if (extension == ".node" || extension == ".ele") return ReadTetgenMesh(path);
  if (extension == ".vtk") return ReadVtkMesh(path);
  throw InputError(path, 0, "",
                   "unknown mesh file extension '" + extension +
                       "'; expected .msh (Gmsh), .node/.ele (TetGen) or .vtk (legacy VTK)");
}

}  // namespace hapsim::fem
