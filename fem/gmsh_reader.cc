// Gmsh MSH reader: ASCII 2.x and 4.1 read here, line by line, with errors at their line; the other
// versions (1, 4.0, binary 2.x and 4.x) by Gmsh's own reader (libgmsh, in a child process). Format
// reference: the Gmsh manual, "MSH file format" (4.1) and "Legacy formats / MSH file format
// version 2".

#include <limits>
#include <string>
#include <vector>

#include "core/error.h"
#include "fem/gmsh_library.h"
#include "fem/mesh_io.h"
#include "fem/mesh_text_reader.h"

namespace hapsim::fem {
namespace {

using internal::GmshVolumeMesh;
using internal::MakeTetMeshFromGmsh;
using internal::MeshTextReader;
using internal::RawNode;
using internal::RawTet;
using internal::ReadTetsWithGmsh;
using internal::RunGmshInChildProcess;
using Tokens = std::vector<std::string>;

constexpr int kGmshTet4 = 4;    // Gmsh element type of the linear 4-node tetrahedron
constexpr int kGmshTet10 = 11;  // and of the quadratic 10-node one (fem/quadratic_tet.h's order)

// The tetrahedra this reader takes, and their node counts (0: another type).
int TetNodeCount(long long type) { return type == kGmshTet4 ? 4 : type == kGmshTet10 ? 10 : 0; }

// kLibrary: a format this reader leaves to Gmsh's own (MSH 1, binary, 4.0).
enum class MshVersion { k2, k41, kLibrary };

// A section being read: its name without '$' and the line of its header.
struct Section {
  std::string name;
  int line;

  std::string key() const { return "$" + name; }  // the error key, e.g. "$Nodes"
};

// What the node and element sections hold.
struct GmshContent {
  std::vector<RawNode> nodes;
  std::vector<RawTet> tets;
  int nodes_line = 0;     // line of $Nodes, 0 if none
  int elements_line = 0;  // line of $Elements, 0 if none
  int num_other_elements = 0;
  // The sections a file holds at most once, with the line each was seen on.
  std::vector<std::pair<std::string, int>> single_sections;
};

// Names the Gmsh volume element types other than the 4- and 10-node tets, nullptr for other types.
const char* OtherVolumeElementName(long long type) {
  struct TypeName {
    int type;
    const char* name;
  };
  static constexpr TypeName kVolumeTypes[] = {
      {5, "8-node hexahedron"},    {6, "6-node prism"},         {7, "5-node pyramid"},
      {12, "27-node hexahedron"},  {13, "18-node prism"},       {14, "14-node pyramid"},
      {17, "20-node hexahedron"},  {18, "15-node prism"},       {19, "13-node pyramid"},
      {29, "20-node tetrahedron"}, {30, "35-node tetrahedron"}, {31, "56-node tetrahedron"},
      {92, "64-node hexahedron"},  {93, "125-node hexahedron"}};
  for (const TypeName& entry : kVolumeTypes)
    if (entry.type == type) return entry.name;
  return nullptr;
}

// Gmsh's point, line, triangle and quadrangle types (first to fifth order): elements a volume
// mesh file also holds (boundaries, physical groups), which this reader skips. Any other type
// that is not a volume is not a Gmsh element type at all (e.g. 0) and is an error.
bool IsLowerDimensionalType(long long type) {
  static constexpr int kTypes[] = {15,                              // point
                                   1,  8,  26, 27, 28,              // lines
                                   2,  9,  20, 21, 22, 23, 24, 25,  // triangles
                                   3,  10, 16, 36, 37};             // quadrangles
  for (const int known : kTypes)
    if (known == type) return true;
  return false;
}

[[noreturn]] void FailUnknownType(const MeshTextReader& reader, const Section& section,
                                  long long type) {
  reader.Fail(section.key(),
              "element type " + std::to_string(type) +
                  " is not a Gmsh element type this reader knows (4 and 11: tetrahedra "
                  "of 4 and 10 nodes; points, lines, triangles and quadrangles are "
                  "skipped)");
}

[[noreturn]] void FailUnsupportedVolume(const MeshTextReader& reader, const Section& section,
                                        long long type) {
  const char* name = OtherVolumeElementName(type);
  reader.Fail(section.key(),
              "unsupported volume element " + std::string(name ? name : "type") + " (type " +
                  std::to_string(type) +
                  "); hapsim reads tetrahedra of 4 nodes (type 4) or 10 (type 11): mesh with "
                  "a tetrahedral 3D algorithm and Mesh.ElementOrder 1 or 2");
}

// Reads the tokens of the next entry of `section`; `expected` names it for messages (e.g.
// "node 3 of 8 (count on line 5)"). Throws at end of file, or when a '$' line comes first
// (the declared count is larger than the number of entries).
Tokens ReadEntry(MeshTextReader* reader, const Section& section, const std::string& expected) {
  Tokens tokens;
  if (!reader->NextTokens(&tokens, false))
    reader->Fail(section.key(), "unexpected end of file in the section starting on line " +
                                    std::to_string(section.line) + ": expected " + expected);
  if (tokens[0][0] == '$')
    reader->Fail(section.key(), "found '" + tokens[0] + "' where " + expected +
                                    " was expected: the section has fewer entries than "
                                    "its count says");
  return tokens;
}

// Throws unless `tokens` has exactly `count` entries; `layout` describes them.
void ExpectTokenCount(const MeshTextReader& reader, const Section& section, const Tokens& tokens,
                      size_t count, const std::string& layout) {
  if (tokens.size() != count)
    reader.Fail(section.key(), "expected " + std::to_string(count) + " values (" + layout +
                                   "), found " + std::to_string(tokens.size()));
}

// Reads the line that must end `section`; `after` says what was read (for messages).
void ExpectSectionEnd(MeshTextReader* reader, const Section& section, const std::string& after) {
  Tokens tokens;
  const std::string end = "$End" + section.name;
  if (!reader->NextTokens(&tokens, false))
    reader->Fail(section.key(), "unexpected end of file: expected " + end + " after " + after +
                                    " (section starts on line " + std::to_string(section.line) +
                                    ")");
  if (tokens[0] != end)
    reader->Fail(section.key(), "expected " + end + " after " + after + ", found '" + tokens[0] +
                                    "': the section has more entries than its count says, "
                                    "or is missing " +
                                    end);
}

// Parses a count or size field: a non-negative integer that fits an int.
int ParseCount(const MeshTextReader& reader, const Section& section, const std::string& token,
               const std::string& what) {
  const long long value = reader.ParseInteger(token, section.key(), what);
  if (value < 0 || value > std::numeric_limits<int>::max())
    reader.Fail(section.key(), what + " must be between 0 and 2^31-1, found " + token);
  return static_cast<int>(value);
}

// Parses a node or element tag, which Gmsh requires to be positive.
long long ParseTag(const MeshTextReader& reader, const Section& section, const std::string& token,
                   const std::string& what) {
  const long long tag = reader.ParseInteger(token, section.key(), what);
  if (tag <= 0) reader.Fail(section.key(), what + " must be positive, found " + token);
  return tag;
}

std::string OrdinalOf(int i, int count, int count_line) {
  return std::to_string(i + 1) + " of " + std::to_string(count) + " (count on line " +
         std::to_string(count_line) + ")";
}

// Reads $MeshFormat (which must open the file) through $EndMeshFormat and returns the version:
// ASCII 2.x and 4.1 are read here; MSH 1 (which opens with $NOD), 4.0 and binary 2.x and 4.x by
// Gmsh's own reader (kLibrary). Throws for anything else.
MshVersion ReadMeshFormat(MeshTextReader* reader) {
  Tokens tokens;
  if (!reader->NextTokens(&tokens, false))
    reader->Fail("$MeshFormat", "the file is empty; expected a Gmsh MSH file");
  if (tokens[0] == "$NOD" || tokens[0] == "$NOE") return MshVersion::kLibrary;  // MSH 1
  if (tokens[0] != "$MeshFormat")
    reader->Fail("$MeshFormat",
                 "not a Gmsh MSH file: expected '$MeshFormat' first, found '" + tokens[0] + "'");
  const Section section{"MeshFormat", reader->line_number()};
  tokens = ReadEntry(reader, section, "'version file-type data-size'");
  ExpectTokenCount(*reader, section, tokens, 3, "version file-type data-size, e.g. 4.1 0 8");
  const double version = reader->ParseReal(tokens[0], "$MeshFormat", "the version");
  const long long file_type = reader->ParseInteger(tokens[1], "$MeshFormat", "the file type");
  reader->ParseInteger(tokens[2], "$MeshFormat", "the data size");
  if (version != 4.1 && version != 4.0 && !(version >= 2.0 && version < 3.0))
    reader->Fail("$MeshFormat", "unsupported MSH version " + tokens[0] +
                                    "; supported: 1, 2.x and 4.x (ASCII or binary)");
  if (file_type == 1 || version == 4.0) return MshVersion::kLibrary;
  if (file_type != 0)
    reader->Fail("$MeshFormat", "file type must be 0 (ASCII), found " + tokens[1]);
  ExpectSectionEnd(reader, section, "the version line");
  return version == 4.1 ? MshVersion::k41 : MshVersion::k2;
}

// Parses "x y z" from tokens[first..first+2] into a node.
Eigen::Vector3d ParsePosition(const MeshTextReader& reader, const Section& section,
                              const Tokens& tokens, size_t first) {
  Eigen::Vector3d p_m;
  for (int k = 0; k < 3; ++k)
    p_m[k] = reader.ParseReal(tokens[first + k], section.key(),
                              std::string("the ") + "xyz"[k] + " coordinate");
  return p_m;
}

// MSH 2: count, then "tag x y z" lines.
void ReadNodesV2(MeshTextReader* reader, const Section& section, GmshContent* content) {
  Tokens tokens = ReadEntry(reader, section, "the node count");
  ExpectTokenCount(*reader, section, tokens, 1, "the node count");
  const int count = ParseCount(*reader, section, tokens[0], "the node count");
  const int count_line = reader->line_number();
  for (int i = 0; i < count; ++i) {
    tokens = ReadEntry(reader, section, "node " + OrdinalOf(i, count, count_line));
    ExpectTokenCount(*reader, section, tokens, 4, "node-tag x y z");
    const long long tag = ParseTag(*reader, section, tokens[0], "the node tag");
    content->nodes.push_back(
        {tag, ParsePosition(*reader, section, tokens, 1), reader->line_number()});
  }
  ExpectSectionEnd(
      reader, section,
      std::to_string(count) + " nodes (count on line " + std::to_string(count_line) + ")");
}

// MSH 2: count, then "tag type num-tags tag... node..." lines.
void ReadElementsV2(MeshTextReader* reader, const Section& section, GmshContent* content) {
  Tokens tokens = ReadEntry(reader, section, "the element count");
  ExpectTokenCount(*reader, section, tokens, 1, "the element count");
  const int count = ParseCount(*reader, section, tokens[0], "the element count");
  const int count_line = reader->line_number();
  for (int i = 0; i < count; ++i) {
    tokens = ReadEntry(reader, section, "element " + OrdinalOf(i, count, count_line));
    if (tokens.size() < 3)
      reader->Fail(section.key(), "expected 'elm-number elm-type number-of-tags ...', found " +
                                      std::to_string(tokens.size()) + " values");
    const long long tag = ParseTag(*reader, section, tokens[0], "the element tag");
    const long long type = reader->ParseInteger(tokens[1], section.key(), "the element type");
    const int num_tags = ParseCount(*reader, section, tokens[2], "the number of tags");
    const int num_nodes = TetNodeCount(type);
    if (num_nodes == 0) {
      if (OtherVolumeElementName(type)) FailUnsupportedVolume(*reader, section, type);
      if (!IsLowerDimensionalType(type)) FailUnknownType(*reader, section, type);
      ++content->num_other_elements;
      continue;
    }
    ExpectTokenCount(*reader, section, tokens, 3 + static_cast<size_t>(num_tags) + num_nodes,
                     "elm-number " + std::to_string(type) + " number-of-tags, " +
                         std::to_string(num_tags) + " tag(s), " + std::to_string(num_nodes) +
                         " node tags");
    RawTet tet{tag, {}, reader->line_number(), num_nodes};
    for (int k = 0; k < num_tags; ++k)
      reader->ParseInteger(tokens[3 + k], section.key(), "an element tag (physical/elementary)");
    for (int a = 0; a < num_nodes; ++a)
      tet.nodes[a] = ParseTag(*reader, section, tokens[3 + num_tags + a], "a node tag");
    content->tets.push_back(tet);
  }
  ExpectSectionEnd(
      reader, section,
      std::to_string(count) + " elements (count on line " + std::to_string(count_line) + ")");
}

// MSH 4.1 node block: "dim tag parametric n", n tag lines, n coordinate lines.
void ReadNodeBlockV41(MeshTextReader* reader, const Section& section, int count, int* total,
                      GmshContent* content) {
  Tokens tokens = ReadEntry(reader, section, "a node block header");
  ExpectTokenCount(*reader, section, tokens, 4, "entityDim entityTag parametric numNodesInBlock");
  const int dim = ParseCount(*reader, section, tokens[0], "the entity dimension");
  const int parametric = ParseCount(*reader, section, tokens[2], "the parametric flag");
  const int n = ParseCount(*reader, section, tokens[3], "the number of nodes in the block");
  const int block_line = reader->line_number();
  if (dim > 3 || parametric > 1)
    reader->Fail(section.key(), "entity dimension must be 0..3 and parametric 0 or 1");
  if (n > count - *total)
    reader->Fail(section.key(), "this block brings the node total to " +
                                    std::to_string(static_cast<long long>(*total) + n) +
                                    ", more than the " + std::to_string(count) + " declared");
  // Tags and their lines (RawNode::line is the tag's line, where a duplicate tag is reported).
  std::vector<std::pair<long long, int>> tags;  // grown per entry: a bogus n must not allocate
  for (int i = 0; i < n; ++i) {
    tokens = ReadEntry(reader, section, "node tag " + OrdinalOf(i, n, block_line));
    ExpectTokenCount(*reader, section, tokens, 1, "one node tag per line");
    tags.emplace_back(ParseTag(*reader, section, tokens[0], "the node tag"), reader->line_number());
  }
  const size_t num_coordinates = 3 + (parametric ? dim : 0);
  for (int i = 0; i < n; ++i) {
    tokens = ReadEntry(reader, section, "node coordinates " + OrdinalOf(i, n, block_line));
    ExpectTokenCount(*reader, section, tokens, num_coordinates,
                     parametric ? "x y z and parametric coordinates" : "x y z");
    content->nodes.push_back(
        {tags[i].first, ParsePosition(*reader, section, tokens, 0), tags[i].second});
  }
  *total += n;
}

// MSH 4.1 element block: "dim tag type n", then n lines "tag node...".
void ReadElementBlockV41(MeshTextReader* reader, const Section& section, int count, int* total,
                         GmshContent* content) {
  Tokens tokens = ReadEntry(reader, section, "an element block header");
  ExpectTokenCount(*reader, section, tokens, 4,
                   "entityDim entityTag elementType numElementsInBlock");
  const int dim = ParseCount(*reader, section, tokens[0], "the entity dimension");
  const long long type = reader->ParseInteger(tokens[2], section.key(), "the element type");
  const int n = ParseCount(*reader, section, tokens[3], "the number of elements in the block");
  const int block_line = reader->line_number();
  const int num_nodes = TetNodeCount(type);
  if (num_nodes == 0 && (dim == 3 || OtherVolumeElementName(type)))
    FailUnsupportedVolume(*reader, section, type);
  if (num_nodes == 0 && !IsLowerDimensionalType(type)) FailUnknownType(*reader, section, type);
  if (n > count - *total)
    reader->Fail(section.key(), "this block brings the element total to " +
                                    std::to_string(static_cast<long long>(*total) + n) +
                                    ", more than the " + std::to_string(count) + " declared");
  for (int i = 0; i < n; ++i) {
    tokens = ReadEntry(reader, section, "element " + OrdinalOf(i, n, block_line));
    const long long tag = ParseTag(*reader, section, tokens[0], "the element tag");
    if (num_nodes == 0) {
      ++content->num_other_elements;
      continue;
    }
    ExpectTokenCount(*reader, section, tokens, 1 + static_cast<size_t>(num_nodes),
                     "elementTag and " + std::to_string(num_nodes) + " node tags");
    RawTet tet{tag, {}, reader->line_number(), num_nodes};
    for (int a = 0; a < num_nodes; ++a)
      tet.nodes[a] = ParseTag(*reader, section, tokens[1 + a], "a node tag");
    content->tets.push_back(tet);
  }
  *total += n;
}

// MSH 4.1 $Nodes or $Elements: "numEntityBlocks num minTag maxTag", then the blocks.
template <typename ReadBlock>
void ReadBlocksV41(MeshTextReader* reader, const Section& section, const std::string& what,
                   ReadBlock read_block, GmshContent* content) {
  Tokens tokens = ReadEntry(reader, section, "the section header");
  ExpectTokenCount(*reader, section, tokens, 4,
                   "numEntityBlocks num" + what + " min" + what + "Tag max" + what + "Tag");
  const int num_blocks = ParseCount(*reader, section, tokens[0], "the number of blocks");
  const int count = ParseCount(*reader, section, tokens[1], "the " + what + " count");
  reader->ParseInteger(tokens[2], section.key(), "the minimum tag");
  reader->ParseInteger(tokens[3], section.key(), "the maximum tag");
  const int count_line = reader->line_number();
  int total = 0;
  for (int b = 0; b < num_blocks; ++b) read_block(reader, section, count, &total, content);
  const std::string after =
      std::to_string(num_blocks) + " blocks (count on line " + std::to_string(count_line) + ")";
  ExpectSectionEnd(reader, section, after);
  if (total != count)
    reader->Fail(section.key(), "the blocks hold " + std::to_string(total) + " entries, but line " +
                                    std::to_string(count_line) + " declares " +
                                    std::to_string(count));
}

// Skips a section this reader does not use ($PhysicalNames, $Entities, $NodeData, ...).
void SkipSection(MeshTextReader* reader, const Section& section) {
  const std::string end = "$End" + section.name;
  Tokens tokens;
  while (reader->NextTokens(&tokens, false)) {
    if (tokens[0] == end) return;
    if (tokens[0][0] == '$' && section.name != "Comments")
      reader->Fail(section.key(), "found '" + tokens[0] + "' inside the section starting on line " +
                                      std::to_string(section.line) + ": missing " + end);
  }
  reader->Fail(section.key(), "unexpected end of file: the section starting on line " +
                                  std::to_string(section.line) + " has no " + end);
}

// Reads one section whose header "$name" was just read.
void ReadSection(MeshTextReader* reader, MshVersion version, const Section& section,
                 GmshContent* content) {
  const bool v2 = version == MshVersion::k2;
  if (section.name == "Nodes" || section.name == "Elements") {
    const bool nodes = section.name == "Nodes";
    int& seen_line = nodes ? content->nodes_line : content->elements_line;
    if (seen_line != 0)
      reader->Fail(section.key(), "a second $" + section.name + " section (the first is on line " +
                                      std::to_string(seen_line) + ")");
    seen_line = section.line;
    if (nodes && v2) ReadNodesV2(reader, section, content);
    if (nodes && !v2) ReadBlocksV41(reader, section, "Node", ReadNodeBlockV41, content);
    if (!nodes && v2) ReadElementsV2(reader, section, content);
    if (!nodes && !v2) ReadBlocksV41(reader, section, "Element", ReadElementBlockV41, content);
  } else if (section.name == "MeshFormat") {
    reader->Fail("$MeshFormat", "a second $MeshFormat section");
  } else if (section.name.rfind("End", 0) == 0) {
    reader->Fail(section.key(), "'$" + section.name + "' without a matching opening line");
  } else {
    // Gmsh writes these once per file; a second one is a corrupt or concatenated file.
    // ($NodeData, $ElementData and $Comments may repeat.)
    static const char* const kOnce[] = {"PhysicalNames", "Entities",      "PartitionedEntities",
                                        "Periodic",      "GhostElements", "Parametrizations"};
    for (const char* once : kOnce) {
      if (section.name != once) continue;
      for (const auto& [name, line] : content->single_sections)
        if (name == section.name)
          reader->Fail(section.key(), "a second $" + section.name +
                                          " section (the first is on line " + std::to_string(line) +
                                          ")");
      content->single_sections.emplace_back(section.name, section.line);
    }
    SkipSection(reader, section);
  }
}

// Gmsh's own reader, in a child process (a file it cannot handle may crash or hang it).
TetMesh ReadWithGmshLibrary(const std::string& path) {
  constexpr double kTimeout_s = 300.0;
  const GmshVolumeMesh made =
      RunGmshInChildProcess([&] { return ReadTetsWithGmsh(path); }, kTimeout_s);
  if (!made.error.empty()) throw InputError(path, 0, "", "Gmsh's reader refused it: " + made.error);
  if (made.tet_tags.empty())
    throw InputError(path, 0, "$Elements",
                     "no tetrahedra (type 4 or 11): is this a surface mesh? (generate a volume "
                     "mesh: gmsh -3)");
  return MakeTetMeshFromGmsh(made, path, "");
}

}  // namespace

TetMesh ReadGmshMesh(const std::string& path) {
  MeshTextReader reader(path);
  const MshVersion version = ReadMeshFormat(&reader);
  if (version == MshVersion::kLibrary) return ReadWithGmshLibrary(path);
  GmshContent content;
  Tokens tokens;
  while (reader.NextTokens(&tokens, false)) {
    if (tokens[0][0] != '$' || tokens.size() != 1 || tokens[0].size() < 2)
      reader.Fail("", "expected a section header such as $Nodes, found '" + tokens[0] + "'");
    ReadSection(&reader, version, Section{tokens[0].substr(1), reader.line_number()}, &content);
  }
  if (content.nodes_line == 0) reader.Fail("$Nodes", "the file has no $Nodes section");
  if (content.elements_line == 0) reader.Fail("$Elements", "the file has no $Elements section");
  if (content.tets.empty())
    throw InputError(path, content.elements_line, "$Elements",
                     "no tetrahedra (type 4 or 11) among the " +
                         std::to_string(content.num_other_elements) +
                         " elements: is this a surface mesh? (generate a volume mesh: gmsh -3)");
  return internal::MakeCheckedTetMesh(content.nodes, path, "$Nodes", content.tets, path,
                                      "$Elements");
}

}  // namespace hapsim::fem
