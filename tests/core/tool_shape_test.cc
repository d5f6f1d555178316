// Tool mass properties and mesh reading against independent values: the closed forms of each
// primitive against finely triangulated meshes through the polyhedral (divergence theorem)
// formula, Richardson-extrapolated; a rotated and translated box mesh against the
// transformation law of inertia (R I Rᵀ, COM moved); OBJ and STL (ASCII, binary) cubes read back
// against the box closed form; every malformed input reported with its file line or triangle.
#include "core/tool_shape.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/rigid_tool.h"
#include "core/shape_mesh.h"
#include "core/triangle_mesh_io.h"

namespace hapsim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDensity_kg_m3 = 7800.0;  // steel

// Summing ~10 rounded terms per face: exact formulas agree to a few hundred ulps.
constexpr double kExactRelTol = 1e-12;

double RelativeError(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return (a - b).norm() / b.norm();
}

// Orients each triangle of a convex mesh that contains the origin outward: the normal must point
// away from the origin. Independent of how the generators order their corners.
void OrientOutwardConvex(TriangleMesh* mesh) {
  for (Eigen::Index f = 0; f < mesh->triangles.cols(); ++f) {
    const Eigen::Vector3d a = mesh->vertices_m.col(mesh->triangles(0, f));
    const Eigen::Vector3d b = mesh->vertices_m.col(mesh->triangles(1, f));
    const Eigen::Vector3d c = mesh->vertices_m.col(mesh->triangles(2, f));
    if ((b - a).cross(c - a).dot(a + b + c) < 0.0) {
      std::swap(mesh->triangles(1, f), mesh->triangles(2, f));
    }
  }
}

// Surface of revolution about z from a profile (ρ_i, z_i) running from the bottom pole (ρ = 0)
// to the top pole (ρ = 0), n_around vertices per ring (inscribed polygons).
TriangleMesh MakeRevolutionMesh(const std::vector<Eigen::Vector2d>& profile, int n_around) {
  const int num_rings = static_cast<int>(profile.size()) - 2;
  TriangleMesh mesh;
  mesh.vertices_m.resize(3, 2 + num_rings * n_around);
  mesh.vertices_m.col(0) << 0, 0, profile.front().y();
  for (int i = 0; i < num_rings; ++i) {
    for (int j = 0; j < n_around; ++j) {
      const double angle = 2.0 * kPi * j / n_around;
      const Eigen::Vector2d& p = profile[i + 1];
      mesh.vertices_m.col(1 + i * n_around + j) << p.x() * std::cos(angle), p.x() * std::sin(angle),
          p.y();
    }
  }
  const int top = 1 + num_rings * n_around;
  mesh.vertices_m.col(top) << 0, 0, profile.back().y();
  std::vector<Eigen::Vector3i> triangles;
  auto ring = [&](int i, int j) { return 1 + i * n_around + (j % n_around); };
  for (int j = 0; j < n_around; ++j) {
    triangles.emplace_back(0, ring(0, j), ring(0, j + 1));
    for (int i = 0; i + 1 < num_rings; ++i) {
      triangles.emplace_back(ring(i, j), ring(i, j + 1), ring(i + 1, j + 1));
      triangles.emplace_back(ring(i, j), ring(i + 1, j + 1), ring(i + 1, j));
    }
    triangles.emplace_back(top, ring(num_rings - 1, j), ring(num_rings - 1, j + 1));
  }
  mesh.triangles.resize(3, static_cast<Eigen::Index>(triangles.size()));
  for (size_t f = 0; f < triangles.size(); ++f) mesh.triangles.col(f) = triangles[f];
  OrientOutwardConvex(&mesh);
  return mesh;
}

// Arc of radius r about (0, z_centre) from latitude φ0 to φ1 in n steps (both ends included).
void AppendArc(double r, double z_centre, double phi0, double phi1, int n,
               std::vector<Eigen::Vector2d>* profile) {
  for (int i = 0; i <= n; ++i) {
    const double phi = phi0 + (phi1 - phi0) * i / n;
    profile->emplace_back(i == 0 && phi0 == -kPi / 2 ? 0.0 : r * std::cos(phi),
                          z_centre + r * std::sin(phi));
  }
  if (phi1 == kPi / 2) profile->back().x() = 0.0;  // exact pole
}

TriangleMesh MakeSphereMesh(double r, int n) {
  std::vector<Eigen::Vector2d> profile;
  AppendArc(r, 0.0, -kPi / 2, kPi / 2, n / 2, &profile);
  return MakeRevolutionMesh(profile, n);
}

TriangleMesh MakeCapsuleMesh(double r, double h, int n) {
  std::vector<Eigen::Vector2d> profile;
  AppendArc(r, -h / 2, -kPi / 2, 0.0, n / 4, &profile);
  AppendArc(r, h / 2, 0.0, kPi / 2, n / 4, &profile);
  return MakeRevolutionMesh(profile, n);
}

TriangleMesh MakeCylinderMesh(double r, double h, int n) {
  return MakeRevolutionMesh({{0, -h / 2}, {r, -h / 2}, {r, h / 2}, {0, h / 2}}, n);
}

// Box as 8 corners (index = x + 2y + 4z bits) and 12 triangles.
TriangleMesh MakeBoxMesh(const Eigen::Vector3d& half) {
  TriangleMesh mesh;
  mesh.vertices_m.resize(3, 8);
  for (int i = 0; i < 8; ++i) {
    mesh.vertices_m.col(i) << (i & 1 ? 1 : -1) * half.x(), (i & 2 ? 1 : -1) * half.y(),
        (i & 4 ? 1 : -1) * half.z();
  }
  mesh.triangles.resize(3, 12);
  mesh.triangles << 0, 0, 4, 4, 0, 0, 2, 2, 0, 0, 1, 1,  //
      2, 3, 5, 7, 1, 5, 6, 7, 4, 6, 3, 7,                //
      3, 1, 7, 6, 5, 4, 7, 3, 6, 2, 7, 5;
  OrientOutwardConvex(&mesh);
  return mesh;
}

ToolShape MeshShape(TriangleMesh mesh) {
  ToolShape shape;
  shape.kind = ToolShape::Kind::kMesh;
  shape.mesh = std::move(mesh);
  return shape;
}

// ---------------------------------------------------------------------------------------------
// 1. Primitives: closed form against the polyhedral formula.

TEST(ToolShapeTest, BoxClosedFormMatchesBoxMeshExactly) {
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m << 0.01, 0.02, 0.035;
  const MassProperties closed = CalcMassProperties(box, kDensity_kg_m3);
  const MassProperties mesh =
      CalcMassProperties(MeshShape(MakeBoxMesh(box.half_extents_m)), kDensity_kg_m3);
  EXPECT_NEAR(closed.mass_kg, kDensity_kg_m3 * 0.02 * 0.04 * 0.07, 1e-15);
  EXPECT_NEAR(mesh.mass_kg / closed.mass_kg, 1.0, kExactRelTol);
  EXPECT_LT(mesh.com_m.norm(), 1e-15);
  EXPECT_LT(RelativeError(mesh.inertia_com_kg_m2, closed.inertia_com_kg_m2), kExactRelTol);
}

// The inscribed polyhedra err by C h² + O(h⁴) (h ∝ 1/n, the error of inscribed polygon areas
// and chords); Richardson extrapolation (4 Q(2n) − Q(n))/3 removes the h² term.
struct Convergence {
  double coarse_error, fine_error, extrapolated_error;
};
Convergence MeasureConvergence(const ToolShape& primitive, TriangleMesh (*make_mesh)(int)) {
  const MassProperties exact = CalcMassProperties(primitive, kDensity_kg_m3);
  const MassProperties coarse = CalcMassProperties(MeshShape(make_mesh(64)), kDensity_kg_m3);
  const MassProperties fine = CalcMassProperties(MeshShape(make_mesh(128)), kDensity_kg_m3);
  const double mass_extrapolated = (4.0 * fine.mass_kg - coarse.mass_kg) / 3.0;
  const Eigen::Matrix3d inertia_extrapolated =
      (4.0 * fine.inertia_com_kg_m2 - coarse.inertia_com_kg_m2) / 3.0;
  EXPECT_LT(fine.com_m.norm(), 1e-12);
  return {RelativeError(coarse.inertia_com_kg_m2, exact.inertia_com_kg_m2),
          RelativeError(fine.inertia_com_kg_m2, exact.inertia_com_kg_m2),
          std::max(std::abs(mass_extrapolated / exact.mass_kg - 1.0),
                   RelativeError(inertia_extrapolated, exact.inertia_com_kg_m2))};
}

// Second order: halving h divides the error by ≈ 4 (3.5–4.5 allows the h⁴ term at n = 64);
// after extrapolation the residual O(h⁴) ~ (2π/64)⁴ ~ 1e-4 times a small constant: 2e-5.
constexpr double kExtrapolatedRelTol = 2e-5;
void ExpectSecondOrderConvergence(const char* name, const Convergence& c) {
  EXPECT_GT(c.coarse_error / c.fine_error, 3.5);
  EXPECT_LT(c.coarse_error / c.fine_error, 4.5);
  EXPECT_LT(c.extrapolated_error, kExtrapolatedRelTol);
  std::printf("  %s inertia error n=64: %.3e, n=128: %.3e, extrapolated: %.3e\n", name,
              c.coarse_error, c.fine_error, c.extrapolated_error);
}

constexpr double kRadius_m = 0.012;
constexpr double kLength_m = 0.05;

TEST(ToolShapeTest, SphereClosedFormIsTheLimitOfSphereMeshes) {
  ToolShape sphere;
  sphere.radius_m = kRadius_m;
  EXPECT_NEAR(CalcMassProperties(sphere, kDensity_kg_m3).mass_kg,
              kDensity_kg_m3 * 4.0 / 3.0 * kPi * std::pow(kRadius_m, 3), 1e-15);
  ExpectSecondOrderConvergence(
      "sphere", MeasureConvergence(sphere, [](int n) { return MakeSphereMesh(kRadius_m, n); }));
}

TEST(ToolShapeTest, CylinderClosedFormIsTheLimitOfPrismMeshes) {
  ToolShape cylinder;
  cylinder.kind = ToolShape::Kind::kCylinder;
  cylinder.radius_m = kRadius_m;
  cylinder.length_m = kLength_m;
  ExpectSecondOrderConvergence("cylinder", MeasureConvergence(cylinder, [](int n) {
                                 return MakeCylinderMesh(kRadius_m, kLength_m, n);
                               }));
}

// A cylinder whose rim is rounded by its own radius is a capsule (a sphere when the length is
// 2r), and by almost nothing the sharp cylinder: the quadrature of the rounded bands against
// those closed forms.
TEST(ToolShapeTest, RoundedCylinderMatchesSphereCapsuleAndSharpCylinder) {
  const auto calc = [](double r, double length, double e) {
    ToolShape shape;
    shape.kind = ToolShape::Kind::kCylinder;
    shape.radius_m = r;
    shape.length_m = length;
    shape.edge_radius_m = e;
    return CalcMassProperties(shape, kDensity_kg_m3);
  };
  const auto expect_same = [](const MassProperties& a, const MassProperties& b, double tolerance) {
    EXPECT_NEAR(a.mass_kg, b.mass_kg, tolerance * b.mass_kg);
    EXPECT_LT((a.inertia_com_kg_m2 - b.inertia_com_kg_m2).norm(),
              tolerance * b.inertia_com_kg_m2.norm());
  };
  ToolShape sphere;
  sphere.radius_m = kRadius_m;
  expect_same(calc(kRadius_m, 2.0 * kRadius_m, kRadius_m),
              CalcMassProperties(sphere, kDensity_kg_m3), 1e-12);
  ToolShape capsule;
  capsule.kind = ToolShape::Kind::kCapsule;
  capsule.radius_m = kRadius_m;
  capsule.length_m = kLength_m;
  expect_same(calc(kRadius_m, kLength_m + 2.0 * kRadius_m, kRadius_m),
              CalcMassProperties(capsule, kDensity_kg_m3), 1e-12);
  expect_same(calc(kRadius_m, kLength_m, 1e-9), calc(kRadius_m, kLength_m, 0.0), 1e-6);
  EXPECT_THROW(calc(kRadius_m, kLength_m, 1.01 * kRadius_m), std::invalid_argument);
  EXPECT_THROW(calc(kRadius_m, kLength_m, -1e-3), std::invalid_argument);
}

TEST(ToolShapeTest, CapsuleClosedFormIsTheLimitOfCapsuleMeshes) {
  ToolShape capsule;
  capsule.kind = ToolShape::Kind::kCapsule;
  capsule.radius_m = kRadius_m;
  capsule.length_m = kLength_m;
  ExpectSecondOrderConvergence("capsule", MeasureConvergence(capsule, [](int n) {
                                 return MakeCapsuleMesh(kRadius_m, kLength_m, n);
                               }));
}

// ---------------------------------------------------------------------------------------------
// 2. A mesh in an arbitrary frame: COM moved, inertia rotated (full 3×3).

TEST(ToolShapeTest, RotatedTranslatedBoxMeshGivesRotatedInertia) {
  const Eigen::Vector3d half(0.01, 0.02, 0.035);
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m = half;
  const MassProperties body = CalcMassProperties(box, kDensity_kg_m3);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix();
  const Eigen::Vector3d p(0.3, -1.2, 2.5);  // far from the origin: tests the re-centring
  TriangleMesh mesh = MakeBoxMesh(half);
  mesh.vertices_m = (R * mesh.vertices_m).colwise() + p;
  const MassProperties moved = CalcMassProperties(MeshShape(mesh), kDensity_kg_m3);
  EXPECT_NEAR(moved.mass_kg / body.mass_kg, 1.0, kExactRelTol);
  EXPECT_LT((moved.com_m - p).norm(), 1e-14);
  const Eigen::Matrix3d expected = R * body.inertia_com_kg_m2 * R.transpose();
  EXPECT_LT(RelativeError(moved.inertia_com_kg_m2, expected), 1e-10);  // coordinates ~ 2.5 m
  EXPECT_GT(std::abs(expected(0, 1)), 1e-3 * expected.norm());         // genuinely full

  const ToolModel model = MakeToolModel(MeshShape(mesh), kDensity_kg_m3);
  EXPECT_LT(model.shape.mesh.vertices_m.rowwise().mean().norm(), 1e-14);  // re-centred on COM
  EXPECT_LT(RelativeError(model.inertia_T_kg_m2, expected), 1e-10);
  const ToolModel light = MakeToolModelWithMass(MeshShape(mesh), 0.01);
  EXPECT_DOUBLE_EQ(light.mass_kg, 0.01);
  EXPECT_LT(RelativeError(light.inertia_T_kg_m2, expected * (0.01 / body.mass_kg)), 1e-10);
}

TEST(ToolShapeTest, OpenInwardOrFlatMeshesAreRejected) {
  TriangleMesh open = MakeBoxMesh({0.01, 0.01, 0.01});
  open.triangles.conservativeResize(3, 11);
  EXPECT_THROW(CalcMassProperties(MeshShape(open), kDensity_kg_m3), std::invalid_argument);
  TriangleMesh inward = MakeBoxMesh({0.01, 0.01, 0.01});
  inward.triangles.row(1).swap(inward.triangles.row(2));
  EXPECT_THROW(CalcMassProperties(MeshShape(inward), kDensity_kg_m3), std::invalid_argument);
  ToolShape sphere;  // zero radius
  EXPECT_THROW(CalcMassProperties(sphere, kDensity_kg_m3), std::invalid_argument);
  sphere.radius_m = 0.01;
  EXPECT_THROW(CalcMassProperties(sphere, 0.0), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// 3. Reading OBJ and STL.

std::string TempPath(const std::string& name) { return ::testing::TempDir() + "hapsim_" + name; }

std::string WriteText(const std::string& name, const std::string& text) {
  const std::string path = TempPath(name);
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// Bit-indexed cube corners (index = x + 2y + 4z), side 2a, as OBJ lines 2–9.
std::string ObjCubeVertices(double a) {
  std::string text = "# cube\n";
  for (int i = 0; i < 8; ++i) {
    text += "v " + std::to_string(i & 1 ? a : -a) + " " + std::to_string(i & 2 ? a : -a) + " " +
            std::to_string(i & 4 ? a : -a) + "\n";
  }
  return text;
}

// Outward quads in every accepted index form, one negative (relative) face; lines 10–17.
const char kObjCubeFaces[] =
    "vn 0 0 1\n"
    "vt 0 0\n"
    "f 1 3 4 2\n"
    "f 5/1 6/1 8/1 7/1\n"
    "f 1//1 2//1 6//1 5//1\n"
    "f 3/1/1 7/1/1 8/1/1 4/1/1\n"
    "f -8 -4 -2 -6\n"
    "f 2 4 8 6\n";

constexpr double kCubeHalf_m = 0.02;

void ExpectCube(const TriangleMesh& mesh) {
  EXPECT_EQ(mesh.vertices_m.cols(), 8);
  EXPECT_EQ(mesh.triangles.cols(), 12);
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m.setConstant(kCubeHalf_m);
  const MassProperties expected = CalcMassProperties(box, kDensity_kg_m3);
  const MassProperties read = CalcMassProperties(MeshShape(mesh), kDensity_kg_m3);
  EXPECT_NEAR(read.mass_kg / expected.mass_kg, 1.0, kExactRelTol);
  EXPECT_LT(RelativeError(read.inertia_com_kg_m2, expected.inertia_com_kg_m2), kExactRelTol);
}

TEST(TriangleMeshIoTest, ObjCubeReadsWithAllIndexForms) {
  const std::string path = WriteText("cube.obj", ObjCubeVertices(kCubeHalf_m) + kObjCubeFaces);
  const TriangleMesh mesh = ReadTriangleMesh(path);
  ExpectCube(mesh);
  EXPECT_EQ(mesh.triangles.col(0), Eigen::Vector3i(0, 2, 3));  // fan of the first quad, as read
  EXPECT_GT(CalcSignedVolume_m3(mesh), 0.0);
}

TEST(TriangleMeshIoTest, InwardObjIsFlipped) {
  std::string faces;  // every quad reversed
  for (const char* quad : {"1 2 4 3", "7 8 6 5", "5 6 2 1", "4 8 7 3", "3 7 5 1", "6 8 4 2"}) {
    faces += std::string("f ") + quad + "\n";
  }
  const TriangleMesh mesh =
      ReadTriangleMesh(WriteText("inward.obj", ObjCubeVertices(kCubeHalf_m) + faces));
  ExpectCube(mesh);
  EXPECT_NEAR(CalcSignedVolume_m3(mesh), std::pow(2 * kCubeHalf_m, 3), 1e-18);
}

std::string StlAscii(const TriangleMesh& mesh) {
  std::string text = "solid cube\n";
  char line[200];
  for (Eigen::Index f = 0; f < mesh.triangles.cols(); ++f) {
    text += "  facet normal 0 0 0\n    outer loop\n";
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = mesh.vertices_m.col(mesh.triangles(k, f));
      std::snprintf(line, sizeof line, "      vertex %.17g %.17g %.17g\n", p.x(), p.y(), p.z());
      text += line;
    }
    text += "    endloop\n  endfacet\n";
  }
  return text + "endsolid cube\n";
}

std::string StlBinary(const TriangleMesh& mesh) {
  std::string bytes = "binary cube";
  bytes.resize(80, ' ');
  const uint32_t n = static_cast<uint32_t>(mesh.triangles.cols());
  bytes.append(reinterpret_cast<const char*>(&n), 4);
  for (uint32_t f = 0; f < n; ++f) {
    float values[12] = {};
    for (int k = 0; k < 3; ++k) {
      for (int d = 0; d < 3; ++d) {
        values[3 + 3 * k + d] = static_cast<float>(mesh.vertices_m(d, mesh.triangles(k, f)));
      }
    }
    bytes.append(reinterpret_cast<const char*>(values), sizeof values);
    bytes.append(2, '\0');
  }
  return bytes;
}

TEST(TriangleMeshIoTest, StlAsciiAndBinaryCubesMergeVertices) {
  const TriangleMesh cube = MakeBoxMesh(Eigen::Vector3d::Constant(kCubeHalf_m));
  // 0.02 is not a float: binary STL stores the nearest float, exact for a power of two.
  const TriangleMesh ascii = ReadTriangleMesh(WriteText("cube_ascii.stl", StlAscii(cube)));
  ExpectCube(ascii);
  for (Eigen::Index f = 0; f < 12; ++f) {  // same corners, in the same order
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(ascii.vertices_m.col(ascii.triangles(k, f)),
                cube.vertices_m.col(cube.triangles(k, f)));
    }
  }
  TriangleMesh cube_pow2 = MakeBoxMesh(Eigen::Vector3d::Constant(0.03125));
  const TriangleMesh binary = ReadTriangleMesh(WriteText("cube_binary.stl", StlBinary(cube_pow2)));
  EXPECT_EQ(binary.vertices_m.cols(), 8);
  EXPECT_EQ(binary.triangles.cols(), 12);
  EXPECT_EQ(binary.vertices_m.cwiseAbs().maxCoeff(), 0.03125);
  EXPECT_NEAR(CalcSignedVolume_m3(binary), std::pow(0.0625, 3), 1e-18);
}

// Expects ReadTriangleMesh(path) to throw InputError at `line` with `key`, message containing
// `fragment`.
void ExpectInputError(const std::string& path, int line, const std::string& key,
                      const std::string& fragment) {
  try {
    ReadTriangleMesh(path);
    ADD_FAILURE() << "no error for " << path;
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_EQ(e.key(), key) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(TriangleMeshIoTest, MalformedObjNamesTheLine) {
  const std::string vertices = ObjCubeVertices(kCubeHalf_m);  // lines 1–9
  ExpectInputError(WriteText("bad_number.obj", "v 0 0 0\nv 1 x 0\n"), 2, "", "'x'");
  ExpectInputError(WriteText("short_v.obj", "\nv 0 0\n"), 2, "", "three coordinates");
  ExpectInputError(WriteText("index0.obj", vertices + "f 0 1 2\n"), 10, "", "index 0");
  ExpectInputError(WriteText("index9.obj", vertices + "f 1 2 9\n"), 10, "", "index 9");
  ExpectInputError(WriteText("index-9.obj", vertices + "f 1 2 -9\n"), 10, "", "index -9");
  ExpectInputError(WriteText("two.obj", vertices + "f 1 2\n"), 10, "", "at least 3");
  ExpectInputError(WriteText("letters.obj", vertices + "f 1 a 2\n"), 10, "", "'a'");
  // Found by fuzzing: a vertex at 1e308 m gave a closed mesh of infinite mass.
  ExpectInputError(WriteText("far.obj", "v 0 0 0\nv 1 1e308 0\n"), 2, "", "beyond 1000 m");
  // Open: the last quad (line 17) left out; its neighbours are on lines 10–14 (not 15).
  std::string faces = kObjCubeFaces;
  faces = faces.substr(0, faces.rfind("f 2 4 8 6"));
  try {
    ReadTriangleMesh(WriteText("open.obj", vertices + faces));
    ADD_FAILURE() << "open mesh accepted";
  } catch (const InputError& e) {
    EXPECT_GE(e.line(), 12);
    EXPECT_LE(e.line(), 16);
    EXPECT_NE(std::string(e.what()).find("not closed"), std::string::npos) << e.what();
  }
  // One quad (line 17) reversed: reported at a line holding a face with a repeated edge.
  faces = std::string(kObjCubeFaces);
  faces.replace(faces.rfind("f 2 4 8 6"), 9, "f 6 8 4 2");
  try {
    ReadTriangleMesh(WriteText("misoriented.obj", vertices + faces));
    ADD_FAILURE() << "misoriented mesh accepted";
  } catch (const InputError& e) {
    EXPECT_GE(e.line(), 12);
    EXPECT_LE(e.line(), 17);
    EXPECT_NE(std::string(e.what()).find("same direction"), std::string::npos) << e.what();
  }
  // Two back-to-back triangles: closed and oriented, but flat.
  ExpectInputError(WriteText("flat.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 2\n"), 0, "",
                   "no volume");
  ExpectInputError(TempPath("missing.obj"), 0, "", "cannot open");
  ExpectInputError(WriteText("cube.ply", "ply\n"), 0, "", "unknown mesh format");
}

TEST(TriangleMeshIoTest, MalformedAsciiStlNamesTheLine) {
  const std::string good = StlAscii(MakeBoxMesh(Eigen::Vector3d::Constant(kCubeHalf_m)));
  // Lines: 1 solid; facet k (0-based) spans lines 2 + 7k … 8 + 7k:
  // facet, outer loop, vertex ×3, endloop, endfacet.
  auto replace_line = [&](int line, const std::string& text) {
    size_t begin = 0;
    for (int i = 1; i < line; ++i) begin = good.find('\n', begin) + 1;
    const size_t end = good.find('\n', begin);
    return good.substr(0, begin) + text + good.substr(end);
  };
  ExpectInputError(WriteText("stl_short.stl", replace_line(11, "vertex 1 2")), 11, "",
                   "three coordinates");
  ExpectInputError(WriteText("stl_nan.stl", replace_line(12, "vertex 1 nan 2")), 12, "", "'nan'");
  ExpectInputError(WriteText("stl_keyword.stl", replace_line(9, "outer loop")), 9, "",
                   "unexpected 'outer'");
  ExpectInputError(WriteText("stl_four.stl", replace_line(14, "vertex 0 0 0")), 14, "",
                   "more than 3");
  ExpectInputError(WriteText("stl_two.stl", replace_line(12, "")), 14, "", "exactly 3");
  ExpectInputError(WriteText("stl_truncated.stl", good.substr(0, good.find("endsolid"))), 85, "",
                   "ends inside");
  ExpectInputError(WriteText("stl_nosolid.stl", "hello\n"), 1, "", "unexpected 'hello'");
  // Open: facet 11 (lines 79–85) removed; the error names the 'facet' line of a neighbour.
  const std::string open = good.substr(0, good.rfind("  facet")) + "endsolid cube\n";
  try {
    ReadTriangleMesh(WriteText("stl_open.stl", open));
    ADD_FAILURE() << "open mesh accepted";
  } catch (const InputError& e) {
    EXPECT_EQ((e.line() - 2) % 7, 0) << e.what();
    EXPECT_NE(std::string(e.what()).find("not closed"), std::string::npos) << e.what();
  }
}

TEST(TriangleMeshIoTest, MalformedBinaryStlNamesTheTriangle) {
  const TriangleMesh cube = MakeBoxMesh(Eigen::Vector3d::Constant(0.03125));
  std::string bytes = StlBinary(cube);
  const float nan = std::nanf("");
  std::memcpy(&bytes[84 + 50 * 5 + 12 + 4], &nan, 4);  // triangle 5, first vertex, y
  ExpectInputError(WriteText("bin_nan.stl", bytes), 0, "triangle 5", "non-finite");
  TriangleMesh open = cube;
  open.triangles.conservativeResize(3, 11);
  try {
    ReadTriangleMesh(WriteText("bin_open.stl", StlBinary(open)));
    ADD_FAILURE() << "open mesh accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 0);
    EXPECT_EQ(e.key().rfind("triangle ", 0), 0u) << e.what();
  }
  // A size that is not 84 + 50 n is read as ASCII (and fails there, at line 1).
  ExpectInputError(WriteText("bin_truncated.stl", bytes.substr(0, bytes.size() - 1)), 1, "",
                   "unexpected");
}

}  // namespace
}  // namespace hapsim

namespace hapsim {
namespace {

// MakeShapeMesh (core/shape_mesh.h): closed and outward, with the volume of the polyhedron that
// has its vertices on the true surface: below the shape's exact volume by the faceting (≤ 1%
// at 64 segments: the inscribed polygon's area ratio sin(2π/n) n/(2π) = 0.9984), above 98% of it.
TEST(ShapeMeshTest, ClosedOutwardAndOfTheShapesVolume) {
  struct Case {
    ToolShape shape;
    double volume_m3;
  };
  auto make = [](ToolShape::Kind kind, double r, double length, double e = 0.0) {
    ToolShape s;
    s.kind = kind;
    s.radius_m = r;
    s.length_m = length;
    s.edge_radius_m = e;
    return s;
  };
  const double r = 0.01, l = 0.04, e = 0.003;
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m = Eigen::Vector3d(0.01, 0.02, 0.03);
  const double kPi = 3.14159265358979323846;
  // Rounded cylinder: Pappus for the rim's quarter discs, swept at the centroid radius.
  const double rim_area = kPi * e * e / 4.0, rim_centroid = (r - e) + 4.0 * e / (3.0 * kPi);
  const double rounded_volume = kPi * (r - e) * (r - e) * l +                        // inner core
                                kPi * (r * r - (r - e) * (r - e)) * (l - 2.0 * e) +  // wall
                                2.0 * (2.0 * kPi * rim_centroid * rim_area);         // two rims
  const Case cases[] = {
      {box, 8.0 * 0.01 * 0.02 * 0.03},
      {make(ToolShape::Kind::kSphere, r, 0.0), 4.0 / 3.0 * kPi * r * r * r},
      {make(ToolShape::Kind::kCapsule, r, l), kPi * r * r * l + 4.0 / 3.0 * kPi * r * r * r},
      {make(ToolShape::Kind::kCylinder, r, l), kPi * r * r * l},
      {make(ToolShape::Kind::kCylinder, r, l, e), rounded_volume},
  };
  for (const Case& c : cases) {
    const TriangleMesh mesh = MakeShapeMesh(c.shape, 64);
    std::string message;
    EXPECT_EQ(FindOpenOrMisorientedTriangle(mesh, &message), -1) << message;
    const double volume_m3 = CalcSignedVolume_m3(mesh);
    EXPECT_LE(volume_m3, c.volume_m3 * (1.0 + 1e-12)) << static_cast<int>(c.shape.kind);
    EXPECT_GT(volume_m3, 0.98 * c.volume_m3) << static_cast<int>(c.shape.kind);
  }
  EXPECT_THROW(MakeShapeMesh(box, 4), std::invalid_argument);
}

}  // namespace
}  // namespace hapsim
