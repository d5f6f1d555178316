#pragma once
// Pieces shared by the mesh readers (fem/mesh_io.h): line-numbered text reading, and the
// conversion of what a reader parsed (file tags, source lines) into a checked TetMesh.

#include <Eigen/Core>
#include <array>
#include <fstream>
#include <string>
#include <vector>

#include "fem/tet_mesh.h"

namespace hapsim::fem::internal {

// Parses all of `token` as an integer or a finite real with std::from_chars (independent of the
// locale; a leading '+' allowed). kOutOfRange: beyond long long or double (subnormals included).
enum class NumberStatus { kOk, kNotANumber, kOutOfRange, kNotFinite };
NumberStatus ParseIntegerToken(const std::string& token, long long* value);
NumberStatus ParseRealToken(const std::string& token, double* value);

// Reads a text file line by line, keeping the 1-based number of the current line so errors can
// point at it.
class MeshTextReader {
 public:
  // Throws InputError(path, 0, ...) if the file is missing, a directory, or cannot be opened.
  explicit MeshTextReader(const std::string& path);

  // Reads the next line that has tokens into *tokens (whitespace-separated; with
  // strip_comments, text from '#' on is dropped first). Returns false at end of file, leaving
  // line_number() at the last line. Throws InputError on a read error.
  bool NextTokens(std::vector<std::string>* tokens, bool strip_comments);

  // Throws InputError(path(), line_number(), key, message).
  [[noreturn]] void Fail(const std::string& key, const std::string& message) const;

  // Parses an integer/real token of the current line; throws via Fail naming `what` if the token
  // is not entirely a number. ParseReal also throws for NaN and Inf.
  long long ParseInteger(const std::string& token, const std::string& key,
                         const std::string& what) const;
  double ParseReal(const std::string& token, const std::string& key, const std::string& what) const;

  const std::string& path() const { return path_; }
  int line_number() const { return line_number_; }

 private:
  std::string path_;
  std::ifstream in_;
  int line_number_ = 0;
};

// A node or tet as read from a file, with the tag/index the file gives it and the source line
// of that tag (for a node of MSH 4.1, the line of its tag, not of its coordinates).
struct RawNode {
  long long tag;
  Eigen::Vector3d p_m;
  int line;
};
struct RawTet {
  long long tag;  // element tag/number, for messages
  // Node tags as in the file: the 4 corners, then for a 10-node (quadratic) tet its 6 edge nodes
  // in Gmsh's order (fem/quadratic_tet.h).
  std::array<long long, 10> nodes;
  int line;
  int num_nodes = 4;  // 4 or 10
};

// Turns what a reader parsed into a TetMesh following the conventions at the top of this file:
// resolves node tags (duplicate tag -> error in node_file, missing tag -> error in tet_file),
// compacts nodes, checks for repeated nodes in a tet, degenerate and inverted tets, and flips an
// all-negative mesh. 10-node tets give a quadratic mesh (all of them: a file may not mix the two),
// whose edge nodes must not fold their tet (FindQuadraticTetProblem). `tets` must be non-empty.
// Errors are thrown at the entry's source line with `node_key`/`tet_key` as key.
TetMesh MakeCheckedTetMesh(const std::vector<RawNode>& nodes, const std::string& node_file,
                           const std::string& node_key, const std::vector<RawTet>& tets,
                           const std::string& tet_file, const std::string& tet_key);

}  // namespace hapsim::fem::internal
