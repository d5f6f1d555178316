// A surface carried by the tets (fem/surface_embedding.h): each point, inside a tet or just
// outside, moves with its tet's linear field, so a rigid motion and a uniform strain of the mesh
// move it exactly as they move the point itself (the map applied to its rest position, an
// independent computation); a point far from every tet is refused, naming it; the boundary as a
// surface of its own puts weight 1 on each node; merging lays the parts out as the nodes are.
// In quadratic tets a point moves with its tet's quadratic field: a quadratic displacement of the
// nodes moves it by that displacement at its own rest position, which linear tets cannot do.
#include "fem/surface_embedding.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>
#include <stdexcept>
#include <string>

#include "fem/lattice_mesher.h"

namespace hapsim::fem {
namespace {

using Eigen::Vector3d;

const TetMesh& Block() {  // 4 × 3 × 2 cm, 1 cm cells: mean edge ≈ 1.2 cm
  static const TetMesh mesh = MakeBoxTetMesh({0.0, 0.0, 0.0}, {0.04, 0.03, 0.02}, {4, 3, 2});
  return mesh;
}

// Random points in the block, then some up to 4 mm outside its faces (the limit is ~6 mm), with
// a triangle through each three in turn.
struct Points {
  Matrix3Xd vertices_m;
  Matrix3Xi triangles;
};
Points MakePoints(int num_inside, int num_outside) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Points points;
  points.vertices_m.resize(3, num_inside + num_outside);
  const Vector3d size_m(0.04, 0.03, 0.02);
  for (int p = 0; p < num_inside + num_outside; ++p) {
    Vector3d q(unit(rng), unit(rng), unit(rng));
    q = q.cwiseProduct(size_m);
    if (p >= num_inside) {  // pushed out through one face, by 0.5–4 mm
      const int axis = p % 3;
      q[axis] =
          (p % 2 == 0) ? -0.0005 - 0.0035 * unit(rng) : size_m[axis] + 0.0005 + 0.0035 * unit(rng);
    }
    points.vertices_m.col(p) = q;
  }
  const int num_points = num_inside + num_outside;
  points.triangles.resize(3, num_points);
  for (int f = 0; f < num_points; ++f)
    points.triangles.col(f) << f, (f + 1) % num_points, (f + 2) % num_points;
  return points;
}

Eigen::VectorXd Stacked(const Matrix3Xd& p_m) {
  return Eigen::Map<const Eigen::VectorXd>(p_m.data(), p_m.size());
}

TEST(SurfaceEmbeddingTest, PointsMoveWithARigidMotionAndAUniformStrainExactly) {
  const Points points = MakePoints(200, 60);
  EmbeddingReport report;
  const EmbeddedSurface surface = EmbedSurface(Block(), points.vertices_m, points.triangles,
                                               CalcDefaultMaxOutsideDistance(Block()), &report);
  EXPECT_EQ(report.num_outside, 60);
  EXPECT_GT(report.max_outside_m, 0.003);
  EXPECT_LE(report.max_outside_m, 0.004 + 1e-12);
  for (int p = 0; p < surface.num_points(); ++p)
    EXPECT_NEAR(surface.weights.col(p).sum(), 1.0, 1e-14);

  Eigen::VectorXd x_points_m;
  // At rest the points are where they were given.
  CalcEmbeddedPositions(surface, Stacked(Block().rest_positions_m), &x_points_m);
  EXPECT_LT((x_points_m - Stacked(points.vertices_m)).cwiseAbs().maxCoeff(), 1e-15);

  // A rigid motion and a uniform strain (any affine map) of the nodes, applied to the points.
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Vector3d(1.0, -2.0, 0.5).normalized()).toRotationMatrix();
  Eigen::Matrix3d F;
  F << 1.2, 0.1, -0.05, 0.0, 0.8, 0.2, 0.1, -0.1, 1.1;
  const Vector3d t_m(0.3, -0.1, 0.05);
  for (const Eigen::Matrix3d& A : {R, F}) {
    const Matrix3Xd x_nodes_m = (A * Block().rest_positions_m).colwise() + t_m;
    CalcEmbeddedPositions(surface, Stacked(x_nodes_m), &x_points_m);
    const Matrix3Xd expected_m = (A * points.vertices_m).colwise() + t_m;
    EXPECT_LT((x_points_m - Stacked(expected_m)).cwiseAbs().maxCoeff(), 1e-12);
  }
}

// u(X) = quadratic in the position, a few mm over the block; applied to every node and point.
Vector3d QuadraticDisplacement_m(const Vector3d& X_m) {
  const Vector3d X = X_m / 0.04;  // over the block's length
  return 0.003 * Vector3d(X.x() * X.x() - 0.5 * X.y() * X.z(), X.x() * X.y() + X.z() * X.z(),
                          -X.y() * X.y() + 0.7 * X.x() * X.z());
}

Matrix3Xd Displaced(const Matrix3Xd& X_m) {
  Matrix3Xd x_m = X_m;
  for (Eigen::Index i = 0; i < X_m.cols(); ++i) x_m.col(i) += QuadraticDisplacement_m(X_m.col(i));
  return x_m;
}

TEST(SurfaceEmbeddingTest, QuadraticTetsCarryAQuadraticFieldExactly) {
  const Points points = MakePoints(200, 60);  // inside, and extrapolated up to 4 mm outside
  const TetMesh quadratic = MakeQuadraticMesh(Block());
  const EmbeddedSurface surface = EmbedSurface(quadratic, points.vertices_m, points.triangles,
                                               CalcDefaultMaxOutsideDistance(Block()));
  ASSERT_EQ(surface.nodes_per_point(), 10);
  for (int p = 0; p < surface.num_points(); ++p)
    EXPECT_NEAR(surface.weights.col(p).sum(), 1.0, 1e-13);
  Eigen::VectorXd x_points_m;
  CalcEmbeddedPositions(surface, Stacked(quadratic.rest_positions_m), &x_points_m);
  EXPECT_LT((x_points_m - Stacked(points.vertices_m)).cwiseAbs().maxCoeff(), 1e-15);
  const Matrix3Xd expected_m = Displaced(points.vertices_m);
  CalcEmbeddedPositions(surface, Stacked(Displaced(quadratic.rest_positions_m)), &x_points_m);
  EXPECT_LT((x_points_m - Stacked(expected_m)).cwiseAbs().maxCoeff(), 1e-15);
  // Linear tets follow the same field only to within a fraction of a millimetre.
  const EmbeddedSurface linear = EmbedSurface(Block(), points.vertices_m, points.triangles,
                                              CalcDefaultMaxOutsideDistance(Block()));
  CalcEmbeddedPositions(linear, Stacked(Displaced(Block().rest_positions_m)), &x_points_m);
  EXPECT_GT((x_points_m - Stacked(expected_m)).cwiseAbs().maxCoeff(), 1e-5);
}

// A quadratic body beside a linear one: the linear part's points are padded to ten nodes with
// weight 0, and each part still moves as its own.
TEST(SurfaceEmbeddingTest, MergingLinearAndQuadraticPartsKeepsEachPartsMotion) {
  const Points points = MakePoints(20, 5);
  const TetMesh quadratic = MakeQuadraticMesh(Block());
  const double limit_m = CalcDefaultMaxOutsideDistance(Block());
  const EmbeddedSurface linear_part =
      EmbedSurface(Block(), points.vertices_m, points.triangles, limit_m);
  const EmbeddedSurface quadratic_part =
      EmbedSurface(quadratic, points.vertices_m, points.triangles, limit_m);
  const int n = Block().num_nodes();
  const EmbeddedSurface merged = MergeEmbeddedSurfaces(
      {linear_part, quadratic_part},
      {ExtractBoundarySurface(Block()), ExtractBoundarySurface(quadratic)}, {0, n});
  ASSERT_EQ(merged.nodes_per_point(), 10);
  Eigen::VectorXd x_nodes_m(3 * (n + quadratic.num_nodes()));
  x_nodes_m << Stacked(Displaced(Block().rest_positions_m)),
      Stacked(Displaced(quadratic.rest_positions_m));
  Eigen::VectorXd x_merged_m, x_linear_m, x_quadratic_m;
  CalcEmbeddedPositions(merged, x_nodes_m, &x_merged_m);
  CalcEmbeddedPositions(linear_part, x_nodes_m.head(3 * n), &x_linear_m);
  CalcEmbeddedPositions(quadratic_part, x_nodes_m.tail(3 * quadratic.num_nodes()), &x_quadratic_m);
  EXPECT_EQ(x_merged_m.head(x_linear_m.size()), x_linear_m);
  EXPECT_EQ(x_merged_m.tail(x_quadratic_m.size()), x_quadratic_m);
}

TEST(SurfaceEmbeddingTest, APointFarOutsideIsRefusedByNumber) {
  Points points = MakePoints(10, 0);
  const double limit_m = CalcDefaultMaxOutsideDistance(Block());
  // Half the mean of edges between 1 cm (the cells') and √3 cm (their diagonals).
  EXPECT_GT(limit_m, 0.005);
  EXPECT_LT(limit_m, 0.0087);
  points.vertices_m.col(6) = Vector3d(0.02, 0.015, 0.02 + 1.5 * limit_m);  // above the top face
  try {
    EmbedSurface(Block(), points.vertices_m, points.triangles, limit_m);
    FAIL() << "a point 1.5 limits out was embedded";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("surface vertex 7 "), std::string::npos)
        << error.what();
    EXPECT_NE(std::string(error.what()).find("outside every tet"), std::string::npos);
  }
  // Just inside the limit it binds.
  points.vertices_m.col(6) = Vector3d(0.02, 0.015, 0.02 + 0.9 * limit_m);
  EXPECT_NO_THROW(EmbedSurface(Block(), points.vertices_m, points.triangles, limit_m));
}

TEST(SurfaceEmbeddingTest, TheBoundaryAsASurfaceWeighsEachNodeOnce) {
  const Matrix3Xi boundary = ExtractBoundarySurface(Block());
  const EmbeddedSurface own = MakeNodeSurface(boundary);
  Eigen::VectorXd x_points_m;
  const Eigen::VectorXd x_nodes_m = Eigen::VectorXd::Random(3 * Block().num_nodes());
  CalcEmbeddedPositions(own, x_nodes_m, &x_points_m);
  for (int f = 0; f < own.num_triangles(); ++f)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(x_points_m.segment<3>(3 * own.triangles(k, f)),
                x_nodes_m.segment<3>(3 * boundary(k, f)));
  // The same surface embedded by location binds each point to a tet holding its node.
  Matrix3Xd vertices_m(3, own.num_points());
  for (int p = 0; p < own.num_points(); ++p)
    vertices_m.col(p) = Block().rest_positions_m.col(own.nodes(0, p));
  const EmbeddedSurface located = EmbedSurface(Block(), vertices_m, own.triangles, 1e-9);
  CalcEmbeddedPositions(located, x_nodes_m, &x_points_m);
  Eigen::VectorXd x_own_m;
  CalcEmbeddedPositions(own, x_nodes_m, &x_own_m);
  EXPECT_LT((x_points_m - x_own_m).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(SurfaceEmbeddingTest, MergingOffsetsNodesAndPointsAndFillsTheBoundary) {
  const Points points = MakePoints(5, 0);
  const EmbeddedSurface part = EmbedSurface(Block(), points.vertices_m, points.triangles, 1e-3);
  const Matrix3Xi boundary = ExtractBoundarySurface(Block());
  const int n = Block().num_nodes();
  // Body 0 without a surface (its boundary), body 1 with one, nodes n.. 2n.
  const EmbeddedSurface merged =
      MergeEmbeddedSurfaces({EmbeddedSurface(), part}, {boundary, boundary}, {0, n});
  const EmbeddedSurface own = MakeNodeSurface(boundary);
  ASSERT_EQ(merged.num_points(), own.num_points() + part.num_points());
  ASSERT_EQ(merged.num_triangles(), own.num_triangles() + part.num_triangles());
  Eigen::VectorXd x_nodes_m(6 * n);
  x_nodes_m << Stacked(Block().rest_positions_m),
      Stacked(Block().rest_positions_m.colwise() + Vector3d(1.0, 0.0, 0.0));
  Eigen::VectorXd x_points_m;
  CalcEmbeddedPositions(merged, x_nodes_m, &x_points_m);
  for (int p = 0; p < part.num_points(); ++p)
    EXPECT_LT((x_points_m.segment<3>(3 * (own.num_points() + p)) -
               (points.vertices_m.col(p) + Vector3d(1.0, 0.0, 0.0)))
                  .norm(),
              1e-15);
  EXPECT_EQ(merged.triangles.col(own.num_triangles()),
            (part.triangles.col(0).array() + own.num_points()).matrix());
  EXPECT_TRUE(MergeEmbeddedSurfaces({EmbeddedSurface()}, {boundary}, {0}).empty());
}

// Two small blocks a thousand kilometres apart: the search grid stays small (its cells grow with
// the spread, at most ~8 per tet), and each point finds its own block.
TEST(SurfaceEmbeddingTest, PiecesFarApartAreSearchedWithoutAHugeGrid) {
  const TetMesh near = MakeBoxTetMesh({0.0, 0.0, 0.0}, {0.01, 0.01, 0.01}, {1, 1, 1});
  TetMesh both = near;
  both.rest_positions_m.resize(3, 2 * near.num_nodes());
  both.rest_positions_m << near.rest_positions_m,
      near.rest_positions_m.colwise() + Vector3d(1e6, 0.0, 0.0);
  both.tets.resize(4, 2 * near.num_tets());
  both.tets << near.tets, near.tets.array() + near.num_nodes();
  Matrix3Xd points_m(3, 3);
  points_m << 0.003, 1e6 + 0.007, 0.005, 0.004, 0.002, 0.005, 0.005, 0.006, 0.0103;
  const Matrix3Xi triangle = (Matrix3Xi(3, 1) << 0, 1, 2).finished();
  const EmbeddedSurface surface = EmbedSurface(both, points_m, triangle, 0.001);
  EXPECT_LT(surface.nodes.col(0).maxCoeff(), near.num_nodes());
  EXPECT_GE(surface.nodes.col(1).minCoeff(), near.num_nodes());
  Eigen::VectorXd x_points_m;
  CalcEmbeddedPositions(surface, Stacked(both.rest_positions_m), &x_points_m);
  EXPECT_LT((x_points_m - Stacked(points_m)).cwiseAbs().maxCoeff(), 1e-9);
}

}  // namespace
}  // namespace hapsim::fem
