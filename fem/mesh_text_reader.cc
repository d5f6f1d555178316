// Shared pieces of the mesh readers; see fem/mesh_text_reader.h.

#include "fem/mesh_text_reader.h"

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
#include "fem/quadratic_tet.h"

namespace hapsim::fem::internal {
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

NumberStatus ParseIntegerToken(const std::string& token, long long* value) {
  const char* first = NumberStart(token);
  const char* last = token.data() + token.size();
  const auto [end, error] = std::from_chars(first, last, *value);
  if (error == std::errc::result_out_of_range) return NumberStatus::kOutOfRange;
  if (error != std::errc() || end != last) return NumberStatus::kNotANumber;
  return NumberStatus::kOk;
}

NumberStatus ParseRealToken(const std::string& token, double* value) {
  const char* first = NumberStart(token);
  const char* last = token.data() + token.size();
  const auto [end, error] = std::from_chars(first, last, *value);
  if (error == std::errc::result_out_of_range) return NumberStatus::kOutOfRange;
  if (error != std::errc() || end != last) return NumberStatus::kNotANumber;
  if (!std::isfinite(*value)) return NumberStatus::kNotFinite;
  return NumberStatus::kOk;
}

long long MeshTextReader::ParseInteger(const std::string& token, const std::string& key,
                                       const std::string& what) const {
  long long value = 0;
  switch (ParseIntegerToken(token, &value)) {
    case NumberStatus::kOk:
      break;
    case NumberStatus::kOutOfRange:
      Fail(key, what + " '" + token + "' is out of range");
    default:
      Fail(key, "expected an integer for " + what + ", found '" + token + "'");
  }
  return value;
}

double MeshTextReader::ParseReal(const std::string& token, const std::string& key,
                                 const std::string& what) const {
  double value = 0.0;
  switch (ParseRealToken(token, &value)) {
    case NumberStatus::kOk:
      break;
    case NumberStatus::kOutOfRange:
      Fail(key, what + " '" + token + "' is out of the range of a double");
    case NumberStatus::kNotFinite:
      Fail(key, what + " is not finite ('" + token + "')");
    default:
      Fail(key, "expected a number for " + what + ", found '" + token + "'");
  }
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
    if (!std::isfinite(quality))  // a node at 1e308 m: the volume overflows (found by fuzzing)
      throw InputError(file, raw_tets[t].line, key,
                       "tetrahedron " + std::to_string(raw_tets[t].tag) +
                           " has a volume that is not a finite number: a node coordinate is too "
                           "large (units are metres)");
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
    // Corners 2 and 3 swapped: edges (1,2) and (3,1), and (2,0) and (3,0), trade places.
    if (mesh->is_quadratic()) {
      mesh->edge_nodes.row(1).swap(mesh->edge_nodes.row(5));
      mesh->edge_nodes.row(2).swap(mesh->edge_nodes.row(3));
    }
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
  std::unordered_map<long long, int> line_of_tet_tag;  // a repeated tag: a corrupt file
  for (const RawTet& tet : tets) {
    const auto [it, added] = line_of_tet_tag.emplace(tet.tag, tet.line);
    if (!added)
      throw InputError(tet_file, tet.line, tet_key,
                       "duplicate element tag " + std::to_string(tet.tag) + " (first on line " +
                           std::to_string(it->second) + ")");
  }
  const int nodes_per_tet = tets.front().num_nodes;
  std::vector<std::array<int, 10>> tet_nodes(tets.size());  // positions in `nodes`
  std::vector<bool> used(nodes.size(), false);
  for (size_t t = 0; t < tets.size(); ++t) {
    if (tets[t].num_nodes != nodes_per_tet)
      throw InputError(tet_file, tets[t].line, tet_key,
                       "tetrahedron " + std::to_string(tets[t].tag) + " has " +
                           std::to_string(tets[t].num_nodes) + " nodes where the first has " +
                           std::to_string(nodes_per_tet) +
                           ": a mesh is all linear (4-node) or all quadratic (10-node) tets");
    for (int a = 0; a < nodes_per_tet; ++a) {
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
  if (nodes_per_tet == kP2Nodes) mesh.edge_nodes.resize(6, static_cast<Eigen::Index>(tets.size()));
  for (size_t t = 0; t < tets.size(); ++t)
    for (int a = 0; a < nodes_per_tet; ++a) {
      const int node = compact[tet_nodes[t][a]];
      if (a < 4)
        mesh.tets(a, static_cast<Eigen::Index>(t)) = node;
      else
        mesh.edge_nodes(a - 4, static_cast<Eigen::Index>(t)) = node;
    }
  CheckAndOrientTets(tets, tet_file, tet_key, &mesh);
  if (mesh.is_quadratic())
    for (int t = 0; t < mesh.num_tets(); ++t) {
      P2Nodes X_m;
      for (int a = 0; a < kP2Nodes; ++a) X_m.col(a) = mesh.rest_positions_m.col(mesh.node(a, t));
      if (const auto problem = FindQuadraticTetProblem(X_m))
        throw InputError(tet_file, tets[t].line, tet_key,
                         "tetrahedron " + std::to_string(tets[t].tag) + ": " + *problem);
    }
  // What is left for FindRestMeshProblem to find (tets that disagree on an edge's node) is an
  // input error too, at the line of the tet it names.
  int bad_tet = -1;
  if (const auto problem = FindRestMeshProblem(mesh, &bad_tet))
    throw InputError(tet_file, bad_tet >= 0 ? tets[static_cast<size_t>(bad_tet)].line : 0, tet_key,
                     *problem + " (tet numbers count the file's tetrahedra from 0)");
  HAPSIM_INVARIANT(!FindRestMeshProblem(mesh).has_value());
  return mesh;
}

}  // namespace hapsim::fem::internal
