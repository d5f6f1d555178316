// Surfaces filled with tets (fem/surface_mesher.h) against closed forms: a sphere's volume, its
// surface nodes on the sphere; grading against the cell size asked; and the refusals.
#include "fem/surface_mesher.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "core/shape_mesh.h"
#include "fem/curved_boundary.h"
#include "fem/quadratic_tet.h"
#include "fem/surface_embedding.h"

namespace hapsim::fem {
namespace {

constexpr double kRadius_m = 0.05;

TriangleMesh MakeSphereSurface(int segments) {
  ToolShape sphere;
  sphere.kind = ToolShape::Kind::kSphere;
  sphere.radius_m = kRadius_m;
  return MakeShapeMesh(sphere, segments);
}

double MeanEdge(const TetMesh& mesh, int e) {
  double sum_m = 0.0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b)
      sum_m +=
          (mesh.rest_positions_m.col(mesh.tets(a, e)) - mesh.rest_positions_m.col(mesh.tets(b, e)))
              .norm();
  return sum_m / 6.0;
}

// A sphere of r = 50 mm given as 128 facets around (its facets lie inside the sphere by at most
// the sagitta, 0.03 % of r), filled at h = r/10: the volume within 1 % of 4/3 π r³, the surface
// nodes on the sphere within the facets' sagitta, the tets' edges near h, and no slivers.
TEST(SurfaceMesher, FillsASphereToItsVolume) {
  const TriangleMesh surface = MakeSphereSurface(128);
  const double h_m = kRadius_m / 10.0;
  const TetMesh mesh = MeshClosedSurface(surface, {h_m, {}, 0.0, 0.0}, "sphere");
  EXPECT_FALSE(FindRestMeshProblem(mesh).has_value());
  const TetMeshQuality quality = CalcTetMeshQuality(mesh);
  const double sphere_m3 = 4.0 / 3.0 * M_PI * std::pow(kRadius_m, 3);
  EXPECT_NEAR(quality.volume_m3 / sphere_m3, 1.0, 0.01);
  RecordProperty("tets", quality.num_tets);
  RecordProperty("volume_vs_sphere", std::to_string(quality.volume_m3 / sphere_m3));
  RecordProperty("min_dihedral_deg", std::to_string(quality.min_dihedral_deg));
  RecordProperty("max_dihedral_deg", std::to_string(quality.max_dihedral_deg));
  // Slivers (dihedral angles near 0° or 180°) would stiffen and slow the FEM; Gmsh's optimiser
  // keeps them away (13° to 157° measured).
  EXPECT_GT(quality.min_dihedral_deg, 5.0);
  EXPECT_LT(quality.max_dihedral_deg, 175.0);
  const double sagitta_m = kRadius_m * (1.0 - std::cos(M_PI / 128.0));
  for (int n : [&] {
         const Matrix3Xi faces = ExtractBoundarySurface(mesh);
         return std::vector<int>(faces.data(), faces.data() + faces.size());
       }())
    ASSERT_NEAR(mesh.rest_positions_m.col(n).norm(), kRadius_m, 2.0 * sagitta_m + 1e-9);
  double mean_edge_m = 0.0;
  for (int e = 0; e < mesh.num_tets(); ++e) mean_edge_m += MeanEdge(mesh, e) / mesh.num_tets();
  EXPECT_GT(mean_edge_m, 0.6 * h_m);
  EXPECT_LT(mean_edge_m, 1.4 * h_m);
}

// The volume of a mesh whose tets may be curved quadratic ones (their ∫ dV by quadrature).
double CalcMeshVolume(const TetMesh& mesh) {
  double volume_m3 = 0.0;
  for (int t = 0; t < mesh.num_tets(); ++t) {
    P2Nodes X_m;
    for (int a = 0; a < kP2Nodes; ++a) X_m.col(a) = mesh.rest_positions_m.col(mesh.node(a, t));
    volume_m3 += MakeQuadraticTetRest(X_m, 1.0, 1.0, 1.0).volume_m3;
  }
  return volume_m3;
}

// Quadratic tets cut from a coarse sphere (h = r/3), their boundary edge nodes moved onto the
// surface (fem/curved_boundary.h): every boundary node, corner or edge, then lies on the sphere,
// and the curved faces recover most of the volume the flat facets cut off (against 4/3 π r³ and
// the mesh with straight edges). Interior edge nodes stay at their midpoints. Moved onto a copy of
// the sphere 1 m away, no move is made (each is longer than a quarter of its edge).
TEST(SurfaceMesher, QuadraticTetsCurvedOntoTheSurface) {
  const TriangleMesh surface = MakeSphereSurface(128);
  const TetMesh linear = MeshClosedSurface(surface, {kRadius_m / 3.0, {}, 0.0, 0.0}, "sphere");
  const TetMesh straight = MakeQuadraticMesh(linear);
  TetMesh curved = straight;
  const CurvedBoundaryReport report =
      MoveBoundaryEdgeNodesOntoSurface(surface.vertices_m, surface.triangles, &curved);
  RecordProperty("boundary_edge_nodes", report.num_boundary_edge_nodes);
  RecordProperty("kept", report.num_kept);
  EXPECT_GT(report.num_boundary_edge_nodes, 100);
  EXPECT_EQ(report.num_moved + report.num_kept, report.num_boundary_edge_nodes);
  EXPECT_GE(report.num_moved, report.num_boundary_edge_nodes * 9 / 10);
  EXPECT_GT(report.max_move_m, 0.0);
  const double sagitta_m = kRadius_m * (1.0 - std::cos(M_PI / 128.0));
  int moved_on_sphere = 0;
  const Matrix3Xi faces = ExtractBoundarySurface(curved);
  std::vector<int> boundary(faces.data(), faces.data() + faces.size());
  std::sort(boundary.begin(), boundary.end());
  boundary.erase(std::unique(boundary.begin(), boundary.end()), boundary.end());
  for (int n : boundary) {
    const double off_m = std::abs(curved.rest_positions_m.col(n).norm() - kRadius_m);
    if (n < linear.num_nodes())
      EXPECT_LE(off_m, 2.0 * sagitta_m + 1e-9) << n;
    else if (off_m <= 2.0 * sagitta_m + 1e-9)
      ++moved_on_sphere;
  }
  EXPECT_EQ(moved_on_sphere, report.num_moved);
  int interior_moved = 0;
  for (int n = linear.num_nodes(); n < curved.num_nodes(); ++n)
    if (!std::binary_search(boundary.begin(), boundary.end(), n))
      interior_moved += curved.rest_positions_m.col(n) != straight.rest_positions_m.col(n);
  EXPECT_EQ(interior_moved, 0);
  EXPECT_FALSE(FindRestMeshProblem(curved).has_value());
  const double sphere_m3 = 4.0 / 3.0 * M_PI * std::pow(kRadius_m, 3);
  const double straight_error = CalcMeshVolume(straight) / sphere_m3 - 1.0;
  const double curved_error = CalcMeshVolume(curved) / sphere_m3 - 1.0;
  RecordProperty("straight_volume_error", std::to_string(straight_error));
  RecordProperty("curved_volume_error", std::to_string(curved_error));
  EXPECT_LT(straight_error, -0.02);  // the facets of a coarse mesh cut the sphere's volume
  EXPECT_LT(std::abs(curved_error), 0.25 * std::abs(straight_error));

  TriangleMesh far = surface;
  far.vertices_m.row(0).array() += 1.0;
  TetMesh unchanged = straight;
  const CurvedBoundaryReport refused =
      MoveBoundaryEdgeNodesOntoSurface(far.vertices_m, far.triangles, &unchanged);
  EXPECT_EQ(refused.num_moved, 0);
  EXPECT_EQ(refused.num_kept, refused.num_boundary_edge_nodes);
  EXPECT_TRUE(unchanged.rest_positions_m == straight.rest_positions_m);
  TetMesh linear_copy = linear;
  EXPECT_THROW(
      MoveBoundaryEdgeNodesOntoSurface(surface.vertices_m, surface.triangles, &linear_copy),
      std::invalid_argument);
}

// A finer sphere (other vertices than the one the tets were curved onto) carried by the curved
// quadratic tets: each vertex bound by Newton's method in its curved tet lies exactly where it
// was given at rest, and follows an affine motion of the nodes exactly (the isoparametric map
// reproduces linear fields, curved or not).
TEST(SurfaceMesher, ASurfaceEmbeddedInCurvedTetsSitsOnItAtRestAndMovesAffinely) {
  const TriangleMesh surface = MakeSphereSurface(128);
  TetMesh curved =
      MakeQuadraticMesh(MeshClosedSurface(surface, {kRadius_m / 3.0, {}, 0.0, 0.0}, "sphere"));
  MoveBoundaryEdgeNodesOntoSurface(surface.vertices_m, surface.triangles, &curved);
  const TriangleMesh finer = MakeSphereSurface(200);
  const EmbeddedSurface carried = EmbedSurface(curved, finer.vertices_m, finer.triangles,
                                               CalcDefaultMaxOutsideDistance(curved));
  ASSERT_EQ(carried.nodes_per_point(), 10);
  const auto stacked = [](const Matrix3Xd& p_m) {
    return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(p_m.data(), p_m.size()));
  };
  Eigen::VectorXd x_points_m;
  CalcEmbeddedPositions(carried, stacked(curved.rest_positions_m), &x_points_m);
  EXPECT_LT((x_points_m - stacked(finer.vertices_m)).cwiseAbs().maxCoeff(), 1e-12);
  Eigen::Matrix3d F;
  F << 1.1, 0.2, 0.0, -0.1, 0.9, 0.3, 0.05, 0.0, 1.2;
  const Eigen::Vector3d t_m(0.01, -0.02, 0.03);
  CalcEmbeddedPositions(carried, stacked((F * curved.rest_positions_m).colwise() + t_m),
                        &x_points_m);
  EXPECT_LT((x_points_m - stacked((F * finer.vertices_m).colwise() + t_m)).cwiseAbs().maxCoeff(),
            1e-12);
}

// Graded: within the refine radius of the point the tets are about the refine size, far from it
// about the cell size.
TEST(SurfaceMesher, RefinesNearAPoint) {
  const TriangleMesh surface = MakeSphereSurface(64);
  SurfaceMeshOptions options{0.012, {Eigen::Vector3d(0.0, 0.0, kRadius_m)}, 0.004, 0.012};
  const TetMesh mesh = MeshClosedSurface(surface, options, "sphere");
  double near_sum_m = 0.0, far_sum_m = 0.0;
  int near_count = 0, far_count = 0;
  for (int e = 0; e < mesh.num_tets(); ++e) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) centroid += 0.25 * mesh.rest_positions_m.col(mesh.tets(k, e));
    const double distance_m = (centroid - options.refine_near_m[0]).norm();
    if (distance_m < options.refine_radius_m) near_sum_m += MeanEdge(mesh, e), ++near_count;
    if (distance_m > 3.0 * options.refine_radius_m) far_sum_m += MeanEdge(mesh, e), ++far_count;
  }
  ASSERT_GT(near_count, 10);
  ASSERT_GT(far_count, 10);
  EXPECT_LT(near_sum_m / near_count, 1.5 * options.refine_cell_size_m);
  EXPECT_GT(far_sum_m / far_count, 0.6 * options.cell_size_m);
}

void ExpectRefused(const TriangleMesh& surface, const SurfaceMeshOptions& options,
                   const std::string& key, const std::string& words) {
  try {
    MeshClosedSurface(surface, options, "organ.obj");
    ADD_FAILURE() << "no error for key " << key;
  } catch (const InputError& error) {
    EXPECT_EQ(error.file(), "organ.obj");
    EXPECT_EQ(error.key(), key);
    EXPECT_NE(std::string(error.what()).find(words), std::string::npos) << error.what();
  }
}

TEST(SurfaceMesher, RefusesBadOptionsAndSurfaces) {
  const TriangleMesh sphere = MakeSphereSurface(32);
  ExpectRefused(sphere, {0.0, {}, 0.0, 0.0}, "cell_size_m", "positive");
  ExpectRefused(sphere, {NAN, {}, 0.0, 0.0}, "cell_size_m", "positive");
  ExpectRefused(sphere, {1e-5, {}, 0.0, 0.0}, "cell_size_m", "choose larger cells");
  ExpectRefused(sphere, {0.01, {Eigen::Vector3d::Zero()}, 0.02, 0.01}, "refine.cell_size_m",
                "(0, cell_size_m]");
  ExpectRefused(sphere, {0.01, {Eigen::Vector3d::Zero()}, 0.005, -1.0}, "refine.radius_m",
                "positive");
  // Two spheres in one file: overlapping (the surface crosses itself), and apart.
  for (const double offset_m : {0.03, 0.3}) {
    TriangleMesh two;
    two.vertices_m.resize(3, 2 * sphere.vertices_m.cols());
    two.vertices_m << sphere.vertices_m,
        sphere.vertices_m.colwise() + Eigen::Vector3d(offset_m, 0.0, 0.0);
    two.triangles.resize(3, 2 * sphere.triangles.cols());
    two.triangles << sphere.triangles,
        (sphere.triangles.array() + static_cast<int>(sphere.vertices_m.cols())).matrix();
    ExpectRefused(two, {0.01, {}, 0.0, 0.0}, "surface", "2 separate closed pieces");
  }
  // One piece that crosses itself: the top vertex pulled down through the bottom.
  TriangleMesh pierced = sphere;
  Eigen::Index top;
  pierced.vertices_m.row(2).maxCoeff(&top);
  pierced.vertices_m.col(top) = Eigen::Vector3d(0.0, 0.0, -1.5 * kRadius_m);
  ASSERT_GT(CalcSignedVolume_m3(pierced), 0.0);
  ExpectRefused(pierced, {0.01, {}, 0.0, 0.0}, "surface", "cross itself");
}

// Flat-faced surfaces of a few triangles (a box's 12; Gmsh's partitioner alone loops forever on a
// tetrahedron's 4, so they are subdivided first): the new surface nodes lie on the flat faces,
// so the tets fill exactly the volume of the box.
TEST(SurfaceMesher, FillsAFewFlatTrianglesExactly) {
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m = Eigen::Vector3d(0.02, 0.03, 0.01);
  const TetMesh mesh = MeshClosedSurface(MakeShapeMesh(box), {0.008, {}, 0.0, 0.0}, "box");
  EXPECT_NEAR(CalcTetMeshQuality(mesh).volume_m3, 0.04 * 0.06 * 0.02, 1e-12 * 0.04 * 0.06 * 0.02);
  TriangleMesh tetrahedron;
  tetrahedron.vertices_m.resize(3, 4);
  tetrahedron.vertices_m << 0, 0.01, 0, 0, 0, 0, 0.01, 0, 0, 0, 0, 0.01;
  tetrahedron.triangles.resize(3, 4);
  tetrahedron.triangles << 0, 0, 0, 1, 2, 3, 1, 2, 1, 2, 3, 3;  // outward: (0 2 1) … (1 2 3)
  ASSERT_NEAR(CalcSignedVolume_m3(tetrahedron), 1e-6 / 6.0, 1e-18);
  const TetMesh filled = MeshClosedSurface(tetrahedron, {0.002, {}, 0.0, 0.0}, "tetrahedron");
  EXPECT_NEAR(CalcTetMeshQuality(filled).volume_m3, 1e-6 / 6.0, 1e-12 * 1e-6);
}

// Gmsh runs in a child process with a deadline: one past it is killed, and the caller gets an
// error, not a hang.
TEST(SurfaceMesher, StopsAMesherPastItsTime) {
  try {
    MeshClosedSurface(MakeSphereSurface(64), {0.003, {}, 0.0, 0.0}, "sphere", {2'000'000, 0.05});
    ADD_FAILURE() << "a 30,000-tet mesh in 50 ms";
  } catch (const InputError& error) {
    EXPECT_EQ(error.key(), "surface");
    EXPECT_NE(std::string(error.what()).find("did not finish within"), std::string::npos)
        << error.what();
  }
}

}  // namespace
}  // namespace hapsim::fem
