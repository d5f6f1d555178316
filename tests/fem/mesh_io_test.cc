#include "fem/mesh_io.h"

#include <gmsh.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "core/error.h"
#include "fem/quadratic_tet.h"

namespace hapsim::fem {
namespace {

namespace fs = std::filesystem;

// A 2 x 1 x 1 box of two cubes of edge h, each cut into 5 tets (a central tet on one parity of
// corners and four corner tets); the cubes alternate parity so the shared face is conforming.
// The origin and h are not round in binary, so round trips test all 17 digits.
TetMesh MakeTwoCubeMesh() {
  const double h = 0.1;
  const Eigen::Vector3d origin(1.0 / 3.0, -2.0 / 7.0, 1e-3);
  TetMesh mesh;
  mesh.rest_positions_m.resize(3, 12);
  auto node = [](int i, int j, int k) { return i + 3 * (j + 2 * k); };
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 3; ++i)
        mesh.rest_positions_m.col(node(i, j, k)) = origin + h * Eigen::Vector3d(i, j, k);
  std::vector<Eigen::Vector4i> tets;
  for (int cube = 0; cube < 2; ++cube) {
    auto c = [&](int bits) { return node(cube + (bits & 1), (bits >> 1) & 1, (bits >> 2) & 1); };
    const bool even = cube % 2 == 0;  // parity of the central tet's corners
    const int central[4] = {even ? 0 : 1, even ? 3 : 2, even ? 5 : 4, even ? 6 : 7};
    tets.emplace_back(c(central[0]), c(central[1]), c(central[2]), c(central[3]));
    for (int corner = 0; corner < 8; ++corner) {
      const bool corner_even = ((corner & 1) + ((corner >> 1) & 1) + (corner >> 2)) % 2 == 0;
      if (corner_even == even) continue;
      tets.emplace_back(c(corner), c(corner ^ 1), c(corner ^ 2), c(corner ^ 4));
    }
  }
  mesh.tets.resize(4, static_cast<Eigen::Index>(tets.size()));
  for (size_t t = 0; t < tets.size(); ++t) {
    Eigen::Vector4i tet = tets[t];
    if (CalcSignedVolume(mesh.rest_positions_m, tet) < 0) std::swap(tet[2], tet[3]);
    mesh.tets.col(static_cast<Eigen::Index>(t)) = tet;
  }
  return mesh;
}

// 1-based number of the first line of `text` containing `needle` (0 if none), so expected error
// lines are stated by content rather than by counting.
int LineOf(const std::string& text, const std::string& needle) {
  std::istringstream lines(text);
  int number = 0;
  for (std::string line; std::getline(lines, line);) {
    ++number;
    if (line.find(needle) != std::string::npos) return number;
  }
  return 0;
}

int NumLines(const std::string& text) {
  return static_cast<int>(std::count(text.begin(), text.end(), '\n'));
}

// Returns `text` with the first occurrence of `from` replaced by `to` (which must exist).
std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

class MeshIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(::testing::TempDir()) /
           ("hapsim_mesh_io_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string PathOf(const std::string& name) const { return (dir_ / name).string(); }
  std::string Write(const std::string& name, const std::string& text) const {
    std::ofstream(PathOf(name)) << text;
    return PathOf(name);
  }

  fs::path dir_;
};

void ExpectSameMesh(const TetMesh& expected, const TetMesh& actual) {
  ASSERT_EQ(expected.num_nodes(), actual.num_nodes());
  ASSERT_EQ(expected.num_tets(), actual.num_tets());
  EXPECT_TRUE((expected.rest_positions_m.array() == actual.rest_positions_m.array()).all())
      << "positions differ (bit-exact comparison)";
  EXPECT_TRUE(expected.tets == actual.tets);
  EXPECT_TRUE(expected.edge_nodes == actual.edge_nodes);
}

TEST_F(MeshIoTest, TwoCubeMeshIsValid) {
  const TetMesh mesh = MakeTwoCubeMesh();
  EXPECT_EQ(mesh.num_tets(), 10);
  EXPECT_FALSE(FindRestMeshProblem(mesh).has_value());
  double volume_m3 = 0;
  for (int t = 0; t < mesh.num_tets(); ++t)
    volume_m3 += CalcSignedVolume(mesh.rest_positions_m, mesh.tets.col(t));
  EXPECT_NEAR(volume_m3, 2e-3, 1e-15);                 // two cubes of 0.1 m; round-off only
  EXPECT_EQ(ExtractBoundarySurface(mesh).cols(), 20);  // 10 quads, 2 triangles each: conforming
}

TEST_F(MeshIoTest, RoundTripsAreExact) {
  const TetMesh mesh = MakeTwoCubeMesh();
  WriteGmshMesh(mesh, PathOf("v2.msh"), 2);
  WriteGmshMesh(mesh, PathOf("v4.msh"), 4);
  WriteTetgenMesh(mesh, PathOf("box"));
  EXPECT_NE(ReadText(PathOf("v2.msh")).find("\n2.2 0 8\n"), std::string::npos);
  EXPECT_NE(ReadText(PathOf("v4.msh")).find("\n4.1 0 8\n"), std::string::npos);
  ExpectSameMesh(mesh, ReadGmshMesh(PathOf("v2.msh")));
  ExpectSameMesh(mesh, ReadGmshMesh(PathOf("v4.msh")));
  ExpectSameMesh(mesh, ReadTetgenMesh(PathOf("box.node")));
  ExpectSameMesh(mesh, ReadTetgenMesh(PathOf("box.ele")));
  ExpectSameMesh(mesh, ReadTetgenMesh(PathOf("box")));
  ExpectSameMesh(mesh, ReadTetMesh(PathOf("v4.msh")));
  ExpectSameMesh(mesh, ReadTetMesh(PathOf("box.ele")));
  EXPECT_FALSE(fs::exists(PathOf("v2.msh.tmp")));  // renamed, not left behind
}

// A quadratic mesh goes out as Gmsh's 10-node tets (type 11) and comes back the same, edge nodes
// included, whether or not they sit at their midpoints.
TEST_F(MeshIoTest, QuadraticRoundTripsAreExact) {
  TetMesh mesh = MakeQuadraticMesh(MakeTwoCubeMesh());
  mesh.rest_positions_m.col(mesh.edge_nodes(0, 0)) +=
      0.1 * (mesh.rest_positions_m.col(mesh.tets(0, 0)) -
             mesh.rest_positions_m.col(mesh.edge_nodes(0, 0)));
  WriteGmshMesh(mesh, PathOf("p2_v2.msh"), 2);
  WriteGmshMesh(mesh, PathOf("p2_v4.msh"), 4);
  EXPECT_NE(ReadText(PathOf("p2_v4.msh")).find("\n3 1 11 10\n"), std::string::npos);
  ExpectSameMesh(mesh, ReadGmshMesh(PathOf("p2_v2.msh")));
  ExpectSameMesh(mesh, ReadGmshMesh(PathOf("p2_v4.msh")));
}

// The versions read by Gmsh's own reader (libgmsh): files Gmsh wrote from our 4.1 file give the
// same nodes and tets as the file read here: bit for bit in binary, to the 16 digits Gmsh prints
// in ASCII; and a hand-written MSH 1 file ($NOD / $ELM, as older frameworks ship their organs).
TEST_F(MeshIoTest, EveryGmshVersionGivesTheSameMesh) {
  const TetMesh mesh = MakeTwoCubeMesh();
  WriteGmshMesh(mesh, PathOf("ours.msh"), 4);
  const std::vector<std::tuple<double, int, std::string>> versions = {
      {1.0, 0, "v1.msh"},
      {2.2, 1, "v22_binary.msh"},
      {4.1, 1, "v41_binary.msh"},
      {4.0, 0, "v40.msh"}};  // Gmsh 4.8 writes 4.0 in ASCII only
  gmsh::initialize(0, nullptr, false);
  gmsh::option::setNumber("General.Terminal", std::getenv("HAPSIM_GMSH_VERBOSE") ? 1 : 0);
  gmsh::open(PathOf("ours.msh"));
  for (const auto& [version, binary, name] : versions) {
    gmsh::option::setNumber("Mesh.MshFileVersion", version);
    gmsh::option::setNumber("Mesh.Binary", binary);
    gmsh::write(PathOf(name));
  }
  gmsh::finalize();
  for (const auto& [version, binary, name] : versions) {
    SCOPED_TRACE(name);
    const TetMesh read = ReadGmshMesh(PathOf(name));
    if (binary) {
      ExpectSameMesh(mesh, read);
    } else {
      EXPECT_EQ(read.tets, mesh.tets);
      ASSERT_EQ(read.rest_positions_m.cols(), mesh.rest_positions_m.cols());
      EXPECT_LT((read.rest_positions_m - mesh.rest_positions_m).cwiseAbs().maxCoeff(),
                1e-15 * mesh.rest_positions_m.cwiseAbs().maxCoeff());
    }
  }
  EXPECT_EQ(ReadText(PathOf("v1.msh")).rfind("$NOD", 0), 0u);  // MSH 1 indeed

  const TetMesh two = ReadGmshMesh(Write("hand_v1.msh", R"($NOD
5
1 0 0 0
2 1 0 0
3 0 1 0
4 0 0 1
5 0 0 -1
$ENDNOD
$ELM
3
1 2 1 1 3 1 2 3
2 4 1 1 4 1 2 3 4
3 4 1 1 4 1 3 2 5
$ENDELM
)"));
  ASSERT_EQ(two.num_nodes(), 5);
  ASSERT_EQ(two.num_tets(), 2);  // the triangle (type 2) skipped
  EXPECT_EQ(two.rest_positions_m.col(4), Eigen::Vector3d(0, 0, -1));
  EXPECT_EQ(two.tets.col(0), Eigen::Vector4i(0, 1, 2, 3));
  EXPECT_EQ(two.tets.col(1), Eigen::Vector4i(0, 2, 1, 4));
}

TEST_F(MeshIoTest, GmshLibraryFormatsRefuseOtherVolumeElements) {
  // A hexahedron (type 5) in MSH 1: refused with its type named, as the ASCII reader does.
  try {
    ReadGmshMesh(Write("hex_v1.msh", R"($NOD
8
1 0 0 0
2 1 0 0
3 1 1 0
4 0 1 0
5 0 0 1
6 1 0 1
7 1 1 1
8 0 1 1
$ENDNOD
$ELM
1
1 5 1 1 8 1 2 3 4 5 6 7 8
$ENDELM
)"));
    ADD_FAILURE() << "a hexahedron read as tets";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("Gmsh type 5"), std::string::npos) << error.what();
    EXPECT_EQ(error.file(), PathOf("hex_v1.msh"));
  }
}

TEST_F(MeshIoTest, WriterReportsUnopenableFileAndBadVersion) {
  const TetMesh mesh = MakeTwoCubeMesh();
  const std::string bad_path = PathOf("no_such_dir/out.msh");
  try {
    WriteGmshMesh(mesh, bad_path, 2);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), bad_path);
    EXPECT_EQ(e.line(), 0);
  }
  EXPECT_THROW(WriteGmshMesh(mesh, PathOf("out.msh"), 3), InputError);
  EXPECT_FALSE(fs::exists(PathOf("out.msh")));
}

// Gmsh 4.1 with entities, physical names, non-contiguous tags listed out of order, an unused
// point node, and point, line, triangle and tet elements.
constexpr char kGmsh41Mixed[] = R"($MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
1
3 7 "tissue"
$EndPhysicalNames
$Entities
1 1 1 1
1 5 0 0 0
2 0 0 0 1 0 0 0 2 1 -1
3 0 0 0 1 1 0 0 3 2 -1 1
4 0 0 -1 1 1 1 1 7 1 3
$EndEntities
$Nodes
3 6 10 99
0 1 0 1
99
5 0 0
2 3 0 3
30
10
20
0 1 0
0 0 0
1 0 0
3 4 0 2
40
50
0 0 1
0 0 -1
$EndNodes
$Elements
4 6 1 6
0 1 15 1
1 99
1 2 1 1
2 10 20
2 3 2 2
3 10 20 30
4 10 30 20
3 4 4 2
5 10 20 30 40
6 10 30 20 50
$EndElements
)";

TEST_F(MeshIoTest, ReadsGmsh41WithEntitiesSparseTagsAndMixedElements) {
  const TetMesh mesh = ReadGmshMesh(Write("mixed.msh", kGmsh41Mixed));
  ASSERT_EQ(mesh.num_nodes(), 5);  // node 99 is used by no tet
  ASSERT_EQ(mesh.num_tets(), 2);
  // Compact indices in node-section order: 30 -> 0, 10 -> 1, 20 -> 2, 40 -> 3, 50 -> 4.
  Matrix3Xd expected_p(3, 5);
  expected_p << 0, 0, 1, 0, 0,  //
      1, 0, 0, 0, 0,            //
      0, 0, 0, 1, -1;
  EXPECT_TRUE(mesh.rest_positions_m == expected_p);
  Matrix4Xi expected_tets(4, 2);
  expected_tets << 1, 1,  //
      2, 0,               //
      0, 2,               //
      3, 4;
  EXPECT_TRUE(mesh.tets == expected_tets);
}

constexpr char kGmsh22[] = R"($MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
5
3 0 0 0
7 1 0 0
8 0 1 0
9 0 0 1
12 0 0 -1
$EndNodes
$Elements
4
1 2 2 0 1 3 7 8
2 15 2 0 1 3
3 4 2 7 1 3 7 8 9
4 4 2 7 1 3 8 7 12
$EndElements
)";

TEST_F(MeshIoTest, ReadsGmsh22WithSparseTagsAndMixedElements) {
  const TetMesh mesh = ReadGmshMesh(Write("v2.msh", kGmsh22));
  EXPECT_EQ(mesh.num_nodes(), 5);
  EXPECT_EQ(mesh.num_tets(), 2);
  EXPECT_TRUE(mesh.tets.col(1) == Eigen::Vector4i(0, 2, 1, 4));
  // Windows line ends read the same.
  std::string crlf;
  for (const char c : std::string(kGmsh22))
    crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  ExpectSameMesh(mesh, ReadGmshMesh(Write("crlf.msh", crlf)));
}

// Second-order tets (type 11) as Gmsh makes them: a box meshed by the Gmsh API with
// Mesh.ElementOrder 2, written as ASCII 2.2 and 4.1 (read here) and binary 4.1 (read by Gmsh's
// own reader in a child process). Every edge of a box is straight, so Gmsh puts each edge node at
// its edge's midpoint: that every edge node lands on the midpoint of the corners our order
// (fem/quadratic_tet.h kP2EdgeCorners) pairs it with checks the order, which nothing else here
// fixes. The three files give the same mesh.
TEST_F(MeshIoTest, ReadsGmshSecondOrderTetsInItsNodeOrder) {
  gmsh::initialize(0, nullptr, false);
  gmsh::option::setNumber("General.Terminal", std::getenv("HAPSIM_GMSH_VERBOSE") ? 1 : 0);
  gmsh::model::add("box");
  gmsh::model::occ::addBox(0, 0, 0, 0.02, 0.01, 0.01);
  gmsh::model::occ::synchronize();
  gmsh::option::setNumber("Mesh.MeshSizeMax", 0.006);
  gmsh::model::mesh::generate(3);
  gmsh::model::mesh::setOrder(2);
  const std::vector<std::tuple<double, int, std::string>> files = {
      {2.2, 0, "p2_v22.msh"}, {4.1, 0, "p2_v41.msh"}, {4.1, 1, "p2_v41_binary.msh"}};
  for (const auto& [version, binary, name] : files) {
    gmsh::option::setNumber("Mesh.MshFileVersion", version);
    gmsh::option::setNumber("Mesh.Binary", binary);
    gmsh::write(PathOf(name));
  }
  gmsh::finalize();
  TetMesh first;
  for (const auto& [version, binary, name] : files) {
    SCOPED_TRACE(name);
    const TetMesh mesh = ReadGmshMesh(PathOf(name));
    ASSERT_TRUE(mesh.is_quadratic());
    ASSERT_GT(mesh.num_tets(), 10);
    EXPECT_FALSE(FindRestMeshProblem(mesh).has_value());
    double worst_m = 0.0;
    for (int t = 0; t < mesh.num_tets(); ++t)
      for (int k = 0; k < 6; ++k) {
        const Eigen::Vector3d midpoint =
            0.5 * (mesh.rest_positions_m.col(mesh.tets(kP2EdgeCorners[k][0], t)) +
                   mesh.rest_positions_m.col(mesh.tets(kP2EdgeCorners[k][1], t)));
        worst_m =
            std::max(worst_m, (mesh.rest_positions_m.col(mesh.edge_nodes(k, t)) - midpoint).norm());
      }
    EXPECT_LT(worst_m, 1e-12);
    if (first.num_tets() == 0) {
      first = mesh;
    } else {
      EXPECT_EQ(mesh.tets, first.tets);
      EXPECT_EQ(mesh.edge_nodes, first.edge_nodes);
      EXPECT_LT((mesh.rest_positions_m - first.rest_positions_m).cwiseAbs().maxCoeff(), 1e-15);
    }
  }
}

TEST_F(MeshIoTest, AllNegativeFileIsFlippedToPositive) {
  // Both tets of kGmsh22 with two nodes swapped: every tet is negatively oriented.
  std::string text = Replace(kGmsh22, "1 3 7 8 9", "1 3 8 7 9");
  text = Replace(text, "1 3 8 7 12", "1 3 7 8 12");
  const TetMesh mesh = ReadGmshMesh(Write("negative.msh", text));
  EXPECT_FALSE(FindRestMeshProblem(mesh).has_value());
  EXPECT_TRUE(mesh.tets.col(0) == Eigen::Vector4i(0, 2, 3, 1));  // indices 2 and 3 swapped
}

// TetGen, 1-based, with 2 attributes and a boundary marker per point, a region attribute per
// tet, comments and blank lines; its tets are negatively oriented (flipped on reading).
constexpr char kTetgenNode[] = R"(# five points
5  3  2  1

1   0 0 0    0.5 7   1
2   1 0 0    0.5 7   1  # a trailing comment
3   0 1 0    0.5 7   0
4   0 0 1    0.5 7   1
5   0 0 -1   0.5 7   1
)";
constexpr char kTetgenEle[] = R"(2  4  1
# index, nodes, region
1   1 3 2 4   -1
2   1 2 3 5   2.5
)";

TEST_F(MeshIoTest, ReadsTetgenOneBasedWithAttributesAndMarkers) {
  Write("t.node", kTetgenNode);
  Write("t.ele", kTetgenEle);
  const TetMesh mesh = ReadTetgenMesh(PathOf("t"));
  EXPECT_EQ(mesh.num_nodes(), 5);
  ASSERT_EQ(mesh.num_tets(), 2);
  EXPECT_TRUE(mesh.tets.col(0) == Eigen::Vector4i(0, 2, 3, 1));
  EXPECT_TRUE(mesh.tets.col(1) == Eigen::Vector4i(0, 1, 4, 2));
  EXPECT_TRUE(mesh.rest_positions_m.col(4) == Eigen::Vector3d(0, 0, -1));
  // The same mesh 0-based.
  Write("z.node", "5 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 0 0 -1\n");
  Write("z.ele", "2 4 0\n0 0 2 1 3\n1 0 1 2 4\n");
  EXPECT_TRUE(ReadTetMesh(PathOf("z.node")).tets == mesh.tets);
}

struct MalformedCase {
  const char* name;
  std::string text;
  int expected_line;
  const char* expected_key;     // nullptr: not checked
  const char* message_excerpt;  // must appear in what()
};

void ExpectInputError(const std::string& path, const MalformedCase& c) {
  SCOPED_TRACE(c.name);
  try {
    ReadTetMesh(path);
    ADD_FAILURE() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), c.expected_line) << e.what();
    if (c.expected_key) {
      EXPECT_EQ(e.key(), c.expected_key) << e.what();
    }
    EXPECT_NE(std::string(e.what()).find(c.message_excerpt), std::string::npos) << e.what();
    EXPECT_EQ(e.file(), path);
  }
}

TEST_F(MeshIoTest, MalformedGmshReportsTheLine) {
  const std::string base = kGmsh22;
  const std::string v41 = kGmsh41Mixed;
  auto R = [](const std::string& text, const char* from, const char* to) {
    return Replace(text, from, to);
  };
  const std::string short_count = R(base, "$Nodes\n5", "$Nodes\n6");
  const std::string long_count = R(base, "$Nodes\n5", "$Nodes\n4");
  const std::string truncated = base.substr(0, base.find("4 4 2 7"));
  const std::string no_tets =
      R(R(base, "3 4 2 7", "3 2 2 7"), "4 4 2 7 1 3 8 7 12", "4 15 2 0 1 3");
  const std::string hexes = R(v41, "3 4 4 2", "3 4 5 2");
  const std::string mixed = R(base, "1 3 8 7 12", "1 3 7 8 12");  // 1 positive, 1 negative
  const std::string flat = R(base, "12 0 0 -1", "12 1 1 0");      // coplanar with 3 7 8
  const std::vector<MalformedCase> cases = {
      {"version 3", R(base, "2.2 0 8", "3.0 0 8"), 2, "$MeshFormat", "unsupported MSH version"},
      // Declared 4.0 or binary, they go to Gmsh's own reader, which finds a 2.2 ASCII body.
      {"version 4.0", R(base, "2.2 0 8", "4 0 8"), 0, nullptr, "Gmsh's reader refused it"},
      {"binary", R(base, "2.2 0 8", "2.2 1 8"), 0, nullptr, "no tetrahedra (type 4 or 11)"},
      {"not msh", "solid cube\nendsolid\n", 1, "$MeshFormat", "not a Gmsh MSH file"},
      {"empty", "", 0, "$MeshFormat", "empty"},
      {"count too large", short_count, LineOf(base, "$EndNodes"), "$Nodes", "fewer entries"},
      {"count too small", long_count, LineOf(base, "12 0 0 -1"), "$Nodes", "more entries"},
      {"premature eof", truncated, NumLines(truncated), "$Elements", "end of file"},
      {"non-numeric", R(base, "7 1 0 0", "7 1 zero 0"), LineOf(base, "7 1 0 0"), "$Nodes",
       "'zero'"},
      {"nan", R(base, "8 0 1 0", "8 0 nan 0"), LineOf(base, "8 0 1 0"), "$Nodes", "not finite"},
      {"inf", R(base, "9 0 0 1", "9 0 0 -inf"), LineOf(base, "9 0 0 1"), "$Nodes", "not finite"},
      {"missing node tag", R(base, "1 3 8 7 12", "1 3 8 7 13"), LineOf(base, "1 3 8 7 12"),
       "$Elements", "node 13"},
      {"duplicate node tag", R(base, "12 0 0 -1", "8 0 0 -1"), LineOf(base, "12 0 0 -1"), "$Nodes",
       "duplicate node tag 8"},
      {"no tetrahedra", no_tets, LineOf(base, "$Elements"), "$Elements",
       "no tetrahedra (type 4 or 11)"},
      {"hexahedra", hexes, LineOf(v41, "3 4 4 2"), "$Elements", "8-node hexahedron"},
      {"short tet line", R(base, "1 3 7 8 9", "1 3 7 8"), LineOf(base, "1 3 7 8 9"), "$Elements",
       "expected 9 values"},
      {"block total", R(v41, "3 6 10 99", "3 7 10 99"), LineOf(v41, "$EndNodes"), "$Nodes",
       "the blocks hold 6 entries"},
      {"duplicate 4.1 tag", R(v41, "\n50\n", "\n20\n"), LineOf(v41, "40") + 1, "$Nodes",
       "duplicate node tag 20"},
      {"unterminated section", R(v41, "$EndPhysicalNames", ""), LineOf(v41, "$Entities"),
       "$PhysicalNames", "missing $EndPhysicalNames"},
      {"inverted tet", mixed, LineOf(base, "4 4 2 7"), "$Elements", "tetrahedron 4 is inverted"},
      {"degenerate tet", flat, LineOf(base, "4 4 2 7"), "$Elements", "degenerate"},
      // Issue 9: accepted silently before, or a count far beyond the file.
      {"element type 0", R(base, "2 15 2 0 1 3", "2 0 2 0 1 3"), LineOf(base, "2 15 2 0 1 3"),
       "$Elements", "element type 0 is not a Gmsh element type"},
      {"4.1 element type 0", R(v41, "0 1 15 1", "0 1 0 1"), LineOf(v41, "0 1 15 1"), "$Elements",
       "element type 0"},
      {"duplicated $Entities", R(v41, "$EndEntities\n", "$EndEntities\n$Entities\n$EndEntities\n"),
       LineOf(v41, "$EndEntities") + 1, "$Entities",
       "a second $Entities section (the first is on line"},
      {"duplicate element tag", R(base, "4 4 2 7 1 3 8 7 12", "3 4 2 7 1 3 8 7 12"),
       LineOf(base, "4 4 2 7"), "$Elements", "duplicate element tag 3"},
      {"count 2^31 - 1", R(base, "$Nodes\n5", "$Nodes\n2147483647"), LineOf(base, "$EndNodes"),
       "$Nodes", "fewer entries"},
      {"count 2^31", R(base, "$Nodes\n5", "$Nodes\n2147483648"), LineOf(base, "$Nodes") + 1,
       "$Nodes", "node count"},
      // Found by fuzzing: finite coordinates whose volume overflows (NaN quality passed).
      {"node at 1e308", R(base, "3 0 0 0", "3 5 1e308 0"), LineOf(base, "3 4 2 7"), "$Elements",
       "not a finite number"},
  };
  for (size_t i = 0; i < cases.size(); ++i)
    ExpectInputError(Write("bad" + std::to_string(i) + ".msh", cases[i].text), cases[i]);
}

// One second-order tet of the unit corner: its edge nodes at the midpoints (Gmsh's order).
constexpr char kGmshTet10[] = R"($MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
10
1 0 0 0
2 1 0 0
3 0 1 0
4 0 0 1
5 0.5 0 0
6 0.5 0.5 0
7 0 0.5 0
8 0 0 0.5
9 0 0.5 0.5
10 0.5 0 0.5
$EndNodes
$Elements
2
1 11 2 0 1 1 2 3 4 5 6 7 8 9 10
2 2 2 0 1 1 2 3
$EndElements
)";

// Two second-order tets sharing the face (1, 2, 3): the second's edge nodes on that face are the
// first's (7, 6, 5 in its own order), three more below. Node 15 sits where node 7 does.
constexpr char kGmshTwoTet10[] = R"($MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
15
1 0 0 0
2 1 0 0
3 0 1 0
4 0 0 1
5 0.5 0 0
6 0.5 0.5 0
7 0 0.5 0
8 0 0 0.5
9 0 0.5 0.5
10 0.5 0 0.5
11 0 0 -1
12 0 0 -0.5
13 0.5 0 -0.5
14 0 0.5 -0.5
15 0 0.5 0
$EndNodes
$Elements
2
1 11 2 0 1 1 2 3 4 5 6 7 8 9 10
2 11 2 0 1 1 3 2 11 7 6 5 12 13 14
$EndElements
)";

TEST_F(MeshIoTest, SecondOrderTetsMustShareTheirEdgeNodes) {
  const TetMesh mesh = ReadGmshMesh(Write("two_tet10.msh", kGmshTwoTet10));
  ASSERT_TRUE(mesh.is_quadratic());
  EXPECT_EQ(mesh.num_nodes(), 14);                        // node 15 is used by no tet
  EXPECT_EQ(ExtractBoundarySurface(mesh).cols(), 4 * 6);  // the shared face is inside
  // The second tet with node 15 in place of node 7: the two give edge (1, 3) different nodes.
  const std::string cracked = Replace(kGmshTwoTet10, "1 3 2 11 7 6 5", "1 3 2 11 15 6 5");
  ExpectInputError(
      Write("cracked_tet10.msh", cracked),
      {"cracked", cracked, LineOf(kGmshTwoTet10, "2 11 2 0 1"), "$Elements", "cracked along it"});
}

TEST_F(MeshIoTest, SecondOrderTetsAreCheckedAtTheirLine) {
  const TetMesh mesh = ReadGmshMesh(Write("tet10.msh", kGmshTet10));
  ASSERT_TRUE(mesh.is_quadratic());
  EXPECT_EQ(mesh.num_nodes(), 10);
  // Swapping two corners (and the edge nodes with them) gives a negative tet, flipped to ours.
  const std::string negative = Replace(kGmshTet10, "1 2 3 4 5 6 7 8 9 10", "1 2 4 3 5 10 8 7 9 6");
  const TetMesh flipped = ReadGmshMesh(Write("tet10_negative.msh", negative));
  EXPECT_FALSE(FindRestMeshProblem(flipped).has_value());
  const std::vector<MalformedCase> cases = {
      {"edge node at 0.8 of its edge", Replace(kGmshTet10, "5 0.5 0 0", "5 0.8 0 0"),
       LineOf(kGmshTet10, "1 11 2"), "$Elements", "edge node is far off its edge's midpoint"},
      {"a 10-node and a 4-node tet", Replace(kGmshTet10, "2 2 2 0 1 1 2 3", "2 4 2 0 1 1 2 3 4"),
       LineOf(kGmshTet10, "2 2 2 0 1"), "$Elements", "all linear (4-node) or all quadratic"},
      {"short 10-node line", Replace(kGmshTet10, "8 9 10\n", "8 9\n"), LineOf(kGmshTet10, "1 11 2"),
       "$Elements", "10 node tags"},
  };
  for (size_t i = 0; i < cases.size(); ++i)
    ExpectInputError(Write("bad_tet10_" + std::to_string(i) + ".msh", cases[i].text), cases[i]);
}

TEST_F(MeshIoTest, InvertedMinorityIsReportedEvenWhenPositiveIsTheMinority) {
  // Three tets: two negative (the file's convention), one positive: the positive one is wrong.
  std::string text = Replace(kGmsh22, "$Elements\n4", "$Elements\n5");
  text = Replace(text, "1 3 7 8 9", "1 3 8 7 9");
  text = Replace(text, "$EndElements", "5 4 2 7 1 3 7 9 8\n$EndElements");
  ExpectInputError(Write("minority.msh", text),
                   {"positive minority", "", LineOf(text, "4 4 2 7"), "$Elements", "inverted"});
}

TEST_F(MeshIoTest, MalformedTetgenReportsTheLine) {
  const std::string node = kTetgenNode;
  const std::string ele = kTetgenEle;
  auto check = [&](const MalformedCase& c, const std::string& node_text,
                   const std::string& ele_text, const std::string& file) {
    Write("m.node", node_text);
    Write("m.ele", ele_text);
    ExpectInputError(PathOf(file), c);
  };
  check({"gap in numbering", "", LineOf(node, "4   0 0 1"), "point", "consecutively"},
        Replace(node, "4   0 0 1", "6   0 0 1"), ele, "m.node");
  check({"missing column", "", LineOf(node, "3   0 1 0"), "point", "expected 7 values"},
        Replace(node, "0.5 7   0", "0.5 7"), ele, "m.node");
  check({"eof", "", NumLines(node), "point count", "end of file"},
        Replace(node, "5  3  2  1", "6  3  2  1"), ele, "m.node");
  check({"extra point", "", LineOf(node, "5   0 0 -1"), "point count", "more points"},
        Replace(node, "5  3  2  1", "4  3  2  1"), ele, "m.node");
  check({"count 2^31 - 1", "", NumLines(node), "point count", "end of file"},
        Replace(node, "5  3  2  1", "2147483647  3  2  1"), ele, "m.node");
  check({"duplicate tet number", "", LineOf(ele, "2   1 2 3 5"), "tetrahedron",
         "duplicate element tag 1"},
        node, Replace(ele, "2   1 2 3 5", "1   1 2 3 5"), "m.ele");
  check({"2d", "", LineOf(node, "5  3  2  1"), "dimension", "must be 3"},
        Replace(node, "5  3  2  1", "5  2  2  1"), ele, "m.node");
  check({"bad node ref", "", LineOf(ele, "2   1 2 3 5"), "tetrahedron", "node 6"}, node,
        Replace(ele, "2   1 2 3 5", "2   1 2 3 6"), "m.ele");
  check({"quadratic", "", 1, "nodes per tetrahedron", "10-node"}, node,
        Replace(ele, "2  4  1", "2  10  1"), "m.ele");
  // Found by fuzzing: 4 + 2^31-1 attributes overflowed int (UBSan); now a short line.
  check({"attributes 2^31 - 1", "", LineOf(node, "1   0 0 0"), "point", "expected 2147483652"},
        Replace(node, "5  3  2  1", "5  3  2147483647  1"), ele, "m.node");
  // (Last: it leaves a good m.node for the missing-.ele case below.)
  check({"bad token", "", LineOf(ele, "1   1 3 2 4"), "tetrahedron", "'x'"}, node,
        Replace(ele, "1   1 3 2 4", "1   1 3 x 4"), "m.ele");
  // The .ele is missing: the error names it, at line 0.
  fs::remove(PathOf("m.ele"));
  try {
    ReadTetgenMesh(PathOf("m.node"));
    ADD_FAILURE() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), PathOf("m.ele"));
    EXPECT_EQ(e.line(), 0);
  }
}

TEST_F(MeshIoTest, MissingFileAndUnknownExtensionAreLineZero) {
  ExpectInputError(PathOf("absent.msh"), {"missing", "", 0, nullptr, "file not found"});
  ExpectInputError(Write("cube.stl", "solid\n"), {"extension", "", 0, nullptr, "extension"});
}

TEST_F(MeshIoTest, VtkHasHeaderCountsAndFields) {
  const TetMesh mesh = MakeTwoCubeMesh();
  const Matrix3Xd displacement_m = Matrix3Xd::Constant(3, mesh.num_nodes(), 1e-3);
  WriteVtkTetMesh(mesh.rest_positions_m, mesh.tets, {{"displacement_m", &displacement_m}},
                  PathOf("out.vtk"));
  const std::string text = ReadText(PathOf("out.vtk"));
  EXPECT_EQ(text.rfind("# vtk DataFile Version 3.0\n", 0), 0u);
  for (const char* expected :
       {"\nASCII\n", "\nDATASET UNSTRUCTURED_GRID\n", "\nPOINTS 12 double\n", "\nCELLS 10 50\n",
        "\nCELL_TYPES 10\n", "\nPOINT_DATA 12\n", "\nVECTORS displacement_m double\n"})
    EXPECT_NE(text.find(expected), std::string::npos) << expected;
  EXPECT_EQ(NumLines(text), 5 + 12 + 1 + 10 + 1 + 10 + 2 + 12);
  EXPECT_THROW(WriteVtkTetMesh(mesh.rest_positions_m, mesh.tets, {{"bad name", &displacement_m}},
                               PathOf("bad.vtk")),
               InputError);
}

// Legacy VTK (ReadVtkMesh): our own writer's file, the files Gmsh writes (ASCII and big-endian
// binary, with its surface triangles and points among the cells), and a hand-written 5.1 file
// (OFFSETS / CONNECTIVITY) all give the same nodes and tets.
TEST_F(MeshIoTest, VtkFilesGiveTheSameMesh) {
  const TetMesh mesh = MakeTwoCubeMesh();
  WriteVtkTetMesh(mesh.rest_positions_m, mesh.tets, {}, PathOf("ours.vtk"));
  ExpectSameMesh(mesh, ReadVtkMesh(PathOf("ours.vtk")));
  ExpectSameMesh(mesh, ReadTetMesh(PathOf("ours.vtk")));
  WriteGmshMesh(mesh, PathOf("ours.msh"), 4);
  gmsh::initialize(0, nullptr, false);
  gmsh::option::setNumber("General.Terminal", std::getenv("HAPSIM_GMSH_VERBOSE") ? 1 : 0);
  gmsh::open(PathOf("ours.msh"));
  for (const int binary : {0, 1}) {
    gmsh::option::setNumber("Mesh.Binary", binary);
    gmsh::write(PathOf(binary ? "gmsh_binary.vtk" : "gmsh_ascii.vtk"));
  }
  gmsh::finalize();
  EXPECT_NE(ReadText(PathOf("gmsh_binary.vtk")).find("\nBINARY\n"), std::string::npos);
  ExpectSameMesh(mesh, ReadVtkMesh(PathOf("gmsh_binary.vtk")));  // doubles, bit for bit
  const TetMesh ascii = ReadVtkMesh(PathOf("gmsh_ascii.vtk"));
  EXPECT_EQ(ascii.tets, mesh.tets);
  ASSERT_EQ(ascii.rest_positions_m.cols(), mesh.rest_positions_m.cols());
  EXPECT_LT((ascii.rest_positions_m - mesh.rest_positions_m).cwiseAbs().maxCoeff(), 1e-15);

  // Version 5.1: one tet and one triangle, offsets and connectivity.
  const TetMesh one = ReadVtkMesh(Write("v51.vtk", R"(# vtk DataFile Version 5.1
a tet and a face
ASCII
DATASET UNSTRUCTURED_GRID
POINTS 4 float
0 0 0 1 0 0 0 1 0
0 0 1
METADATA
INFORMATION 0

CELLS 3 7
OFFSETS vtktypeint64
0 4 7
CONNECTIVITY vtktypeint64
0 1 2 3 0 1 2
CELL_TYPES 2
10
5
)"));
  ASSERT_EQ(one.num_tets(), 1);
  EXPECT_NEAR(CalcSignedVolume(one.rest_positions_m, one.tets.col(0)), 1.0 / 6.0, 1e-15);
}

TEST_F(MeshIoTest, BadVtkFilesAreRefusedAtTheirLine) {
  const std::string head =
      "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n"
      "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  const std::vector<MalformedCase> cases = {
      {"not vtk", "solid x\n", 1, "header", "not a legacy VTK file"},
      {"polydata",
       "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 1 float\n0 0 0\n", 4,
       "DATASET", "UNSTRUCTURED_GRID"},
      {"hexahedron", head + "CELLS 1 9\n8 0 1 2 3 0 1 2 3\nCELL_TYPES 1\n12\n", 13, "CELL_TYPES",
       "VTK type 12"},
      {"huge count", head + "CELLS 1000000000 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n", 10, "CELLS",
       "is more than the cells' size"},
      {"bad coordinate",
       "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 1 double\n0 x 0\n",
       6, "POINTS", "finite number"},
      {"missing point", head + "CELLS 1 5\n4 0 1 2 7\nCELL_TYPES 1\n10\n", 11, "CELLS", "7"},
      {"no tets", head + "CELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n5\n", 13, "CELL_TYPES",
       "no tetrahedra"},
  };
  for (size_t i = 0; i < cases.size(); ++i)
    ExpectInputError(Write("bad" + std::to_string(i) + ".vtk", cases[i].text), cases[i]);
}

}  // namespace
}  // namespace hapsim::fem
