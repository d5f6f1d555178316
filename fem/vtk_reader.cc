// Legacy VTK reader (fem::ReadVtkMesh): an UNSTRUCTURED_GRID's points and tetrahedra, ASCII or
// BINARY, in the classic cell layout (file versions up to 4.2: CELLS n size, each cell its count
// then its point indices) or the 5.1 layout (CELLS offsets connectivity, then OFFSETS and
// CONNECTIVITY arrays). Written by hand rather than through VTK's own reader: OpenCV viz brings
// VTK's libraries but not its headers, and libvtk9-dev would install 159 more Debian packages
// here (OpenMPI, HDF5: apt-get -s) for a format this small; the reader is bounded (no count
// allocates beyond what the file's bytes can hold) and fuzzed (tests/fuzz/vtk_fuzzer.cc).

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "core/error.h"
#include "fem/mesh_io.h"
#include "fem/mesh_text_reader.h"

namespace hapsim::fem {
namespace {

using internal::RawNode;
using internal::RawTet;

constexpr int kVtkTetra = 10;
constexpr std::size_t kMaxFileBytes = std::size_t{1} << 31;  // 2 GiB

// The file's bytes, read as whitespace-separated tokens (ASCII parts and keywords) or as raw
// big-endian values (BINARY data), keeping the 1-based line of the cursor for messages.
class VtkCursor {
 public:
  explicit VtkCursor(const std::string& path) : path_(path) {
    std::error_code error;
    if (!std::filesystem::is_regular_file(path, error))
      throw InputError(path, 0, "", "file not found (or not a regular file)");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, 0, "", "cannot open the mesh file");
    in.seekg(0, std::ios::end);
    const std::streamoff size = in.tellg();
    if (size < 0 || static_cast<std::size_t>(size) > kMaxFileBytes)
      throw InputError(path, 0, "", "cannot read the mesh file (over 2 GiB?)");
    in.seekg(0);
    bytes_.resize(static_cast<std::size_t>(size));
    if (size > 0 && !in.read(bytes_.data(), size))
      throw InputError(path, 0, "", "cannot read the mesh file");
  }

  // The rest of the current line (without its newline), advancing past it.
  std::string Line() {
    const std::size_t start = pos_;
    while (pos_ < bytes_.size() && bytes_[pos_] != '\n') ++pos_;
    std::string line(bytes_.data() + start, pos_ - start);
    if (pos_ < bytes_.size()) {
      ++pos_;
      ++line_;
    }
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return line;
  }
  // The next token, or "" at end of file.
  std::string Token() {
    while (pos_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[pos_]))) {
      if (bytes_[pos_] == '\n') ++line_;
      ++pos_;
    }
    const std::size_t start = pos_;
    while (pos_ < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
    return std::string(bytes_.data() + start, pos_ - start);
  }
  // Binary data starts after the newline that ends its keyword line.
  void SkipToNextLine() {
    while (pos_ < bytes_.size() && bytes_[pos_] != '\n') ++pos_;
    if (pos_ < bytes_.size()) {
      ++pos_;
      ++line_;
    }
  }
  // `size` bytes of big-endian value, as an unsigned integer of those bytes.
  std::uint64_t BigEndian(std::size_t size, const std::string& key) {
    if (bytes_.size() - pos_ < size) Fail(key, "unexpected end of file in binary data");
    std::uint64_t value = 0;
    for (std::size_t k = 0; k < size; ++k)
      value = (value << 8) | static_cast<unsigned char>(bytes_[pos_ + k]);
    pos_ += size;
    return value;
  }
  std::size_t remaining() const { return bytes_.size() - pos_; }
  int line() const { return line_; }

  [[noreturn]] void Fail(const std::string& key, const std::string& message) const {
    throw InputError(path_, std::max(line_, 1), key, message);
  }

  long long ParseInteger(const std::string& token, const std::string& key,
                         const std::string& what) const {
    if (token.empty()) Fail(key, "unexpected end of file: expected " + what);
    long long value = 0;
    if (internal::ParseIntegerToken(token, &value) != internal::NumberStatus::kOk)
      Fail(key, what + " must be an integer of 64 bits, found '" + token + "'");
    return value;
  }
  double ParseReal(const std::string& token, const std::string& key,
                   const std::string& what) const {
    if (token.empty()) Fail(key, "unexpected end of file: expected " + what);
    double value = 0.0;
    if (internal::ParseRealToken(token, &value) != internal::NumberStatus::kOk)
      Fail(key, what + " must be a finite number, found '" + token + "'");
    return value;
  }

 private:
  std::string path_;
  std::vector<char> bytes_;
  std::size_t pos_ = 0;
  int line_ = 1;
};

// A data type of the legacy format and its size in bytes in a BINARY file (0: not a type).
std::size_t SizeOfType(std::string type) {
  std::transform(type.begin(), type.end(), type.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (type == "float" || type == "int" || type == "unsigned_int" || type == "vtktypeint32")
    return 4;
  if (type == "double" || type == "long" || type == "unsigned_long" || type == "vtktypeint64" ||
      type == "vtkidtype")
    return 8;
  return 0;
}
bool IsReal(const std::string& type) { return type == "float" || type == "double"; }

// Reads `count` values of `type` (ASCII tokens or BINARY big-endian), as doubles for reals or as
// integers, calling take(value) for each.
class ValueReader {
 public:
  ValueReader(VtkCursor* cursor, bool binary, std::string type, std::string key)
      : cursor_(cursor), binary_(binary), type_(std::move(type)), key_(std::move(key)) {
    size_ = SizeOfType(type_);
    if (size_ == 0) cursor_->Fail(key_, "unsupported data type '" + type_ + "'");
    std::transform(type_.begin(), type_.end(), type_.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (binary_) cursor_->SkipToNextLine();
  }
  // Throws when `count` entries of `per_entry` values cannot fit in what is left of the file (a
  // bogus count must not make the caller allocate or loop for long).
  void CheckFits(long long count, long long per_entry = 1) const {
    const std::size_t least = binary_ ? size_ : 2;  // an ASCII value takes a digit and a space
    const unsigned long long room = cursor_->remaining() / least + 1;
    if (count < 0 || static_cast<unsigned long long>(count) > room / per_entry)
      cursor_->Fail(key_, "the count " + std::to_string(count) + " is more than the file holds");
  }
  double Real(const std::string& what) {
    if (!binary_) return cursor_->ParseReal(cursor_->Token(), key_, what);
    const std::uint64_t bits = cursor_->BigEndian(size_, key_);
    double value;
    if (size_ == 4) {
      const std::uint32_t bits32 = static_cast<std::uint32_t>(bits);
      float f;
      std::memcpy(&f, &bits32, 4);
      value = f;
    } else {
      std::memcpy(&value, &bits, 8);
    }
    if (!std::isfinite(value)) cursor_->Fail(key_, what + " must be finite");
    return value;
  }
  long long Integer(const std::string& what) {
    if (!binary_) return cursor_->ParseInteger(cursor_->Token(), key_, what);
    const std::uint64_t bits = cursor_->BigEndian(size_, key_);
    if (size_ == 4) return static_cast<std::int32_t>(static_cast<std::uint32_t>(bits));
    return static_cast<long long>(bits);
  }
  bool real() const { return IsReal(type_); }

 private:
  VtkCursor* cursor_;
  bool binary_;
  std::string type_, key_;
  std::size_t size_ = 0;
};

// Points, lines and surface cells, linear or quadratic (VTK_VERTEX .. VTK_QUAD = 1..9,
// VTK_QUADRATIC_EDGE, _TRIANGLE, _QUAD = 21..23): a volume mesh's boundary or markers, skipped.
// Every other type is a volume cell hapsim cannot use (or unknown): dropping it would leave a hole.
bool IsSkippedCellType(long long type) {
  return (type >= 1 && type <= 9) || (type >= 21 && type <= 23);
}

// The next keyword section: skips tokens until one of `keywords` (upper case), returning it, or ""
// at end of file.
std::string NextSection(VtkCursor* cursor, const std::vector<std::string>& keywords) {
  for (std::string token = cursor->Token(); !token.empty(); token = cursor->Token()) {
    std::string upper = token;
    std::transform(upper.begin(), upper.end(), upper.begin(),
                   [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
    if (std::find(keywords.begin(), keywords.end(), upper) != keywords.end()) return upper;
  }
  return "";
}

// The points after POINTS n type, tagged by their index 0..n−1.
std::vector<RawNode> ReadPoints(VtkCursor* cursor, bool binary) {
  if (NextSection(cursor, {"POINTS"}).empty()) cursor->Fail("POINTS", "no POINTS section");
  const long long num_points = cursor->ParseInteger(cursor->Token(), "POINTS", "the point count");
  if (num_points <= 0) cursor->Fail("POINTS", "the grid has no points");
  ValueReader points(cursor, binary, cursor->Token(), "POINTS");
  points.CheckFits(num_points, 3);
  if (!points.real()) cursor->Fail("POINTS", "point coordinates must be float or double");
  std::vector<RawNode> nodes;
  for (long long i = 0; i < num_points; ++i) {
    Eigen::Vector3d p_m;
    for (int k = 0; k < 3; ++k) p_m[k] = points.Real("a coordinate");
    nodes.push_back({i, p_m, binary ? 0 : cursor->line()});
  }
  return nodes;
}

// Each cell's point indices, and the line it ends on (ASCII classic layout; else 0).
struct Cells {
  std::vector<std::vector<long long>> points;
  std::vector<int> lines;
};

// Classic layout: CELLS n size, then n cells, each its point count and its indices (size values).
void ReadClassicCells(VtkCursor* cursor, bool binary, long long count, long long size,
                      Cells* cells) {
  ValueReader values(cursor, binary, "int", "CELLS");
  values.CheckFits(size);
  long long read = 0;
  for (long long c = 0; c < count; ++c) {
    const long long num_points = values.Integer("a cell's point count");
    if (num_points < 0 || num_points > size - read - 1)  // read < size here: no overflow
      cursor->Fail("CELLS", "cell " + std::to_string(c) + " overruns the declared size " +
                                std::to_string(size));
    std::vector<long long> cell;
    for (long long k = 0; k < num_points; ++k) cell.push_back(values.Integer("a point index"));
    cells->points.push_back(std::move(cell));
    cells->lines.push_back(binary ? 0 : cursor->line());
    read += 1 + num_points;
  }
  if (read != size)
    cursor->Fail("CELLS", "the cells hold " + std::to_string(read) + " values, not the declared " +
                              std::to_string(size));
}

// Version 5.1: CELLS n_offsets n_connectivity, then OFFSETS type (n_offsets values, from 0 to
// n_connectivity, not decreasing) and CONNECTIVITY type (n_connectivity point indices).
void ReadOffsetCells(VtkCursor* cursor, bool binary, long long num_offsets,
                     long long num_connectivity, Cells* cells) {
  if (NextSection(cursor, {"OFFSETS"}).empty()) cursor->Fail("OFFSETS", "no OFFSETS array");
  ValueReader offsets_reader(cursor, binary, cursor->Token(), "OFFSETS");
  offsets_reader.CheckFits(num_offsets);
  std::vector<long long> offsets;
  for (long long i = 0; i < num_offsets; ++i)
    offsets.push_back(offsets_reader.Integer("an offset"));
  if (NextSection(cursor, {"CONNECTIVITY"}).empty())
    cursor->Fail("CONNECTIVITY", "no CONNECTIVITY array");
  ValueReader connectivity_reader(cursor, binary, cursor->Token(), "CONNECTIVITY");
  connectivity_reader.CheckFits(num_connectivity);
  std::vector<long long> connectivity;
  for (long long i = 0; i < num_connectivity; ++i)
    connectivity.push_back(connectivity_reader.Integer("a point index"));
  if (offsets.empty() || offsets.front() != 0 || offsets.back() != num_connectivity)
    cursor->Fail("OFFSETS", "offsets must run from 0 to the connectivity's size " +
                                std::to_string(num_connectivity));
  for (std::size_t c = 0; c + 1 < offsets.size(); ++c) {
    if (offsets[c + 1] < offsets[c] || offsets[c + 1] > num_connectivity)
      cursor->Fail("OFFSETS", "offsets must not decrease nor pass the connectivity's size");
    cells->points.emplace_back(connectivity.begin() + offsets[c],
                               connectivity.begin() + offsets[c + 1]);
    cells->lines.push_back(0);  // the arrays give no line per cell
  }
}

// CELL_TYPES n: the tetrahedra of `cells`; points, lines and surface cells skipped, any other
// type refused.
std::vector<RawTet> ReadTetrahedra(VtkCursor* cursor, bool binary, const Cells& cells) {
  if (NextSection(cursor, {"CELL_TYPES"}).empty()) cursor->Fail("CELL_TYPES", "no CELL_TYPES");
  const long long num_types = cursor->ParseInteger(cursor->Token(), "CELL_TYPES", "the type count");
  if (num_types != static_cast<long long>(cells.points.size()))
    cursor->Fail("CELL_TYPES", "gives " + std::to_string(num_types) + " types for " +
                                   std::to_string(cells.points.size()) + " cells");
  ValueReader types(cursor, binary, "int", "CELL_TYPES");
  types.CheckFits(num_types);
  std::vector<RawTet> tets;
  for (long long c = 0; c < num_types; ++c) {
    const long long type = types.Integer("a cell type");
    const std::vector<long long>& points = cells.points[c];
    if (type == kVtkTetra) {
      if (points.size() != 4)
        cursor->Fail("CELL_TYPES", "tetrahedron " + std::to_string(c) + " has " +
                                       std::to_string(points.size()) + " points, not 4");
      RawTet tet{c, {}, cells.lines[c]};
      std::copy(points.begin(), points.end(), tet.nodes.begin());
      tets.push_back(tet);
    } else if (!IsSkippedCellType(type)) {
      cursor->Fail("CELL_TYPES", "cell " + std::to_string(c) + " is of VTK type " +
                                     std::to_string(type) +
                                     ": not a linear tetrahedron (10), nor a point, line or "
                                     "surface cell to skip; hapsim needs linear 4-node tetrahedra");
    }
  }
  if (tets.empty()) cursor->Fail("CELL_TYPES", "the grid has no tetrahedra (VTK type 10)");
  return tets;
}

}  // namespace

TetMesh ReadVtkMesh(const std::string& path) {
  VtkCursor cursor(path);
  // Header: the version line, a title line, ASCII | BINARY, DATASET UNSTRUCTURED_GRID.
  const std::string version = cursor.Line();
  if (version.rfind("# vtk DataFile Version", 0) != 0)
    throw InputError(path, 1, "header",
                     "not a legacy VTK file: the first line must be '# vtk DataFile Version "
                     "x.y', found '" +
                         version.substr(0, 60) + "'");
  const bool layout_51 = version.find("Version 5") != std::string::npos;
  cursor.Line();  // title
  const std::string format = cursor.Token();
  if (format != "ASCII" && format != "BINARY")
    cursor.Fail("format", "must be ASCII or BINARY, found '" + format + "'");
  const bool binary = format == "BINARY";
  if (cursor.Token() != "DATASET") cursor.Fail("DATASET", "expected 'DATASET UNSTRUCTURED_GRID'");
  const std::string dataset = cursor.Token();
  if (dataset != "UNSTRUCTURED_GRID")
    cursor.Fail("DATASET", "only UNSTRUCTURED_GRID holds tetrahedra, found '" + dataset + "'");

  const std::vector<RawNode> nodes = ReadPoints(&cursor, binary);
  if (NextSection(&cursor, {"CELLS"}).empty()) cursor.Fail("CELLS", "no CELLS section");
  const long long cells_a = cursor.ParseInteger(cursor.Token(), "CELLS", "the cell count");
  const long long cells_b = cursor.ParseInteger(cursor.Token(), "CELLS", "the cells' size");
  if (cells_a < 0 || cells_a > cells_b)  // each cell takes one value at least
    cursor.Fail("CELLS", "the cell count " + std::to_string(cells_a) +
                             " is more than the cells' size " + std::to_string(cells_b) +
                             " allows");
  Cells cells;
  if (layout_51)
    ReadOffsetCells(&cursor, binary, cells_a, cells_b, &cells);
  else
    ReadClassicCells(&cursor, binary, cells_a, cells_b, &cells);
  const std::vector<RawTet> tets = ReadTetrahedra(&cursor, binary, cells);
  return internal::MakeCheckedTetMesh(nodes, path, "POINTS", tets, path, "CELLS");
}

}  // namespace hapsim::fem
