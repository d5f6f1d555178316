// TetGen .node/.ele reader, ReadTetMesh dispatch, and the pieces shared by all readers
// (line-numbered text reading, tag resolution, orientation checks).

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

namespace hapsim::fem {
namespace internal {
namespace {

// Start of the number in `token` for std::from_chars, which rejects a leading '+'.
const char* NumberStart(const std::string& token) {
  const bool plus = token.size() > 1 && token[0] == '+' && token[1] != '-' && token[1] != '+';
  return token.data() + (plus ? 1 : 0);
}

// Formats a double for a message: 6 significant digits, exponent when needed (1e-09, not 0.000000).
std::string FormatReal(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

}  // namespace

MeshTextReader::MeshTextReader(const std::string& path) : path_(path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path, 0, "", "file not found");
  if (std::filesystem::is_directory(path, ec))
    throw InputError(path, 0, "", "is a directory, not a mesh file");
  in_.open(path);
  if (!in_) throw InputError(path, 0, "", "cannot open the file for reading");
}

bool MeshTextReader::NextTokens(std::vector<std::string>* tokens, bool strip_comments) {
  std::string line;
  while (std::getline(in_, line)) {
    ++line_number_;
    if (strip_comments) line.erase(std::min(line.find('#'), line.size()));
    tokens->clear();
    std::istringstream words(line);  // whitespace includes the '\r' of Windows line ends
    for (std::string word; words >> word;) tokens->push_back(word);
    if (!tokens->empty()) return true;
  }
  if (in_.bad()) Fail("", "read error");
  return false;
}

void MeshTextReader::Fail(const std::string& key, const std::string& message) const {
  throw InputError(path_, line_number_, key, message);
}

long long MeshTextReader::ParseInteger(const std::string& token, const std::string& key,
                                       const std::string& what) const {
  const char* first = NumberStart(token);
  const char* last = token.data() + token.size();
  long long value = 0;
  const auto [end, error] = std::from_chars(first, last, value);
  if (error == std::errc::result_out_of_range) Fail(key, what + " '" + token + "' is out of range");
  if (error != std::errc() || end != last)
    Fail(key, "expected an integer for " + what + ", found '" + token + "'");
  return value;
}

double MeshTextReader::ParseReal(const std::string& token, const std::string& key,
                                 const std::string& what) const {
  const char* first = NumberStart(token);
  const char* last = token.data() + token.size();
  double value = 0.0;
  const auto [end, error] = std::from_chars(first, last, value);
  if (error == std::errc::result_out_of_range)
    Fail(key, what + " '" + token + "' is out of the range of a double");
  if (error != std::errc() || end != last)
    Fail(key, "expected a number for " + what + ", found '" + token + "'");
  if (!std::isfinite(value)) Fail(key, what + " is not finite ('" + token + "')");
  return value;
}

namespace {

// Maps each node tag to its position in `nodes`. Throws at the line of a repeated tag.
std::unordered_map<long long, int> IndexNodeTags(const std::vector<RawNode>& nodes,
                                                 const std::string& file, const std::string& key) {
  std::unordered_map<long long, int> index_of_tag;
  index_of_tag.reserve(nodes.size());
  for (int i = 0; i < static_cast<int>(nodes.size()); ++i) {
    const auto [it, inserted] = index_of_tag.emplace(nodes[i].tag, i);
    if (!inserted)
      throw InputError(file, nodes[i].line, key,
                       "duplicate node tag " + std::to_string(nodes[i].tag) +
                           " (first defined on line " + std::to_string(nodes[it->second].line) +
                           ")");
  }
  return index_of_tag;
}

// Checks every tet for degeneracy and a consistent orientation; flips all tets if all are
// negative. Throws at the source line of the first degenerate tet, else of the first tet whose
// orientation is the minority one (ties: the negative ones).
void CheckAndOrientTets(const std::vector<RawTet>& raw_tets, const std::string& file,
                        const std::string& key, TetMesh* mesh) {
  const int num_tets = mesh->num_tets();
  std::vector<bool> is_negative(num_tets);
  int num_negative = 0;
  for (int t = 0; t < num_tets; ++t) {
    const double quality = CalcTetQuality(mesh->rest_positions_m, mesh->tets.col(t));
    if (std::abs(quality) <= kDegenerateTetQuality)
      throw InputError(file, raw_tets[t].line, key,
                       "tetrahedron " + std::to_string(raw_tets[t].tag) +
                           " is degenerate (quality " + FormatReal(quality) +
                           "): its four nodes are coplanar or nearly so");
    is_negative[t] = quality < 0.0;
    num_negative += is_negative[t] ? 1 : 0;
  }
  if (num_negative == num_tets) {  // the file's convention is the opposite of ours
    mesh->tets.row(2).swap(mesh->tets.row(3));
    return;
  }
  const bool negative_is_minority = 2 * num_negative <= num_tets;
  for (int t = 0; t < num_tets; ++t) {
    if (is_negative[t] != negative_is_minority) continue;
    const double volume_m3 = CalcSignedVolume(mesh->rest_positions_m, mesh->tets.col(t));
    const int num_majority = negative_is_minority ? num_tets - num_negative : num_negative;
    throw InputError(file, raw_tets[t].line, key,
                     "tetrahedron " + std::to_string(raw_tets[t].tag) +
                         " is inverted: its signed volume is " + FormatReal(volume_m3) +
                         " m^3, opposite in sign to " + std::to_string(num_majority) + " of the " +
                         std::to_string(num_tets) + " tetrahedra in the file");
  }
}

}  // namespace

TetMesh MakeCheckedTetMesh(const std::vector<RawNode>& nodes, const std::string& node_file,
                           const std::string& node_key, const std::vector<RawTet>& tets,
                           const std::string& tet_file, const std::string& tet_key) {
  HAPSIM_INVARIANT(!tets.empty());
  const std::unordered_map<long long, int> index_of_tag = IndexNodeTags(nodes, node_file, node_key);
  std::vector<std::array<int, 4>> tet_nodes(tets.size());  // positions in `nodes`
  std::vector<bool> used(nodes.size(), false);
  for (size_t t = 0; t < tets.size(); ++t) {
    for (int a = 0; a < 4; ++a) {
      const long long tag = tets[t].nodes[a];
      const auto it = index_of_tag.find(tag);
      if (it == index_of_tag.end())
        throw InputError(tet_file, tets[t].line, tet_key,
                         "tetrahedron " + std::to_string(tets[t].tag) + " refers to node " +
                             std::to_string(tag) + ", which is not in the node list");
      for (int b = 0; b < a; ++b)
        if (tets[t].nodes[b] == tag)
          throw InputError(tet_file, tets[t].line, tet_key,
                           "tetrahedron " + std::to_string(tets[t].tag) + " uses node " +
                               std::to_string(tag) + " twice");
      tet_nodes[t][a] = it->second;
      used[it->second] = true;
    }
  }
  // Compact indices over the used nodes, in node-section order.
  std::vector<int> compact(nodes.size(), -1);
  int num_used = 0;
  for (size_t i = 0; i < nodes.size(); ++i)
    if (used[i]) compact[i] = num_used++;
  TetMesh mesh;
  mesh.rest_positions_m.resize(3, num_used);
  for (size_t i = 0; i < nodes.size(); ++i)
    if (used[i]) mesh.rest_positions_m.col(compact[i]) = nodes[i].p_m;
  mesh.tets.resize(4, static_cast<Eigen::Index>(tets.size()));
  for (size_t t = 0; t < tets.size(); ++t)
    for (int a = 0; a < 4; ++a)
      mesh.tets(a, static_cast<Eigen::Index>(t)) = compact[tet_nodes[t][a]];
  CheckAndOrientTets(tets, tet_file, tet_key, &mesh);
  HAPSIM_INVARIANT(!FindRestMeshProblem(mesh).has_value());
  return mesh;
}

}  // namespace internal

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
  ReadTetgenEntries(
      &reader, count, header_line, 4 + num_attributes + num_markers, "point", layout,
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
      &reader, count, header_line, 5 + num_attributes, "tetrahedron", layout,
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
  throw InputError(path, 0, "",
                   "unknown mesh file extension '" + extension +
                       "'; expected .msh (Gmsh) or .node/.ele (TetGen)");
}

}  // namespace hapsim::fem
