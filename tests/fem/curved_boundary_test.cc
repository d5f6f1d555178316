// fem/curved_boundary.h on one quadratic tet (corners at the origin and the unit axes) and a flat
// surface, the plane z = c, where every move is known in closed form: the bottom face's three edge
// nodes rise by c, the other three would fall by 0.5 − c, more than a quarter of their edges (1
// and √2 long), and stay. Raising the bottom edge nodes of (0,1) and (2,0) by c gives
// det(∂x/∂ξ) = 1 − 4 c (ξ1 + ξ2) (N = 4 L0 L1 and 4 L2 L0 vary with ξ3 through L0; the node of
// (1,2) leaves det alone). At c = 0.1 the tet stays above 0.6 of its straight det: all three
// move. At c = 0.22 either of the two would bring it to 0.12 at a corner: valid for
// FindQuadraticTetProblem, but bent past a fifth of its straight det, so those two stay.
#include "fem/curved_boundary.h"

#include <gtest/gtest.h>

#include "fem/quadratic_tet.h"
#include "tests/fem/test_utilities.h"

namespace hapsim::fem {
namespace {

using test::MakeUnitQuadraticTet;

// The plane z = c as two large triangles (their closest points are the nodes' projections).
void MakePlane(double c, Matrix3Xd* vertices_m, Matrix3Xi* triangles) {
  vertices_m->resize(3, 4);
  *vertices_m << -5, 5, 5, -5,  //
      -5, -5, 5, 5,             //
      c, c, c, c;
  triangles->resize(3, 2);
  *triangles << 0, 0,  //
      1, 2,            //
      2, 3;
}

// Each edge node k at its straight position, raised by c where raised(k).
template <typename Raised>
void ExpectEdgeNodesRaised(const TetMesh& mesh, const TetMesh& straight, double c, Raised raised) {
  for (int k = 0; k < 6; ++k) {
    const int node = mesh.edge_nodes(k, 0);
    const Eigen::Vector3d expected =
        straight.rest_positions_m.col(node) + (raised(k) ? c : 0.0) * Eigen::Vector3d::UnitZ();
    EXPECT_LT((mesh.rest_positions_m.col(node) - expected).norm(), 1e-15) << k;
  }
}

// The unit quadratic tet with its boundary edge nodes moved onto the plane z = c.
struct RaisedTet {
  TetMesh straight = MakeUnitQuadraticTet();
  TetMesh mesh = straight;
  CurvedBoundaryReport report;
};
RaisedTet RaiseOntoPlane(double c) {
  Matrix3Xd vertices_m;
  Matrix3Xi triangles;
  MakePlane(c, &vertices_m, &triangles);
  RaisedTet raised;
  raised.report = MoveBoundaryEdgeNodesOntoSurface(vertices_m, triangles, &raised.mesh);
  return raised;
}

TEST(CurvedBoundary, MovesOntoAFlatSurfaceWhereTheTetStaysWellShaped) {
  const auto [straight, mesh, report] = RaiseOntoPlane(0.1);
  EXPECT_EQ(report.num_boundary_edge_nodes, 6);
  EXPECT_EQ(report.num_moved, 3);
  EXPECT_EQ(report.num_kept, 3);
  EXPECT_NEAR(report.max_move_m, 0.1, 1e-15);
  ExpectEdgeNodesRaised(mesh, straight, 0.1, [](int k) {  // the bottom face's edges
    return kP2EdgeCorners[k][0] != 3 && kP2EdgeCorners[k][1] != 3;
  });
}

TEST(CurvedBoundary, RefusesMovesThatBendTheTetPastAFifthOfItsDeterminant) {
  const TetMesh straight = MakeUnitQuadraticTet();
  // The move alone is one FindQuadraticTetProblem accepts: det 1 − 4 · 0.22 = 0.12 > 0.
  TetMesh raised = straight;
  raised.rest_positions_m.col(raised.edge_nodes(0, 0)).z() = 0.22;
  P2Nodes X_m;
  for (int a = 0; a < kP2Nodes; ++a) X_m.col(a) = raised.rest_positions_m.col(raised.node(a, 0));
  EXPECT_FALSE(FindQuadraticTetProblem(X_m).has_value());
  const RaisedTet raised_onto_plane = RaiseOntoPlane(0.22);
  EXPECT_EQ(raised_onto_plane.report.num_moved, 1);
  EXPECT_EQ(raised_onto_plane.report.num_kept, 5);
  ExpectEdgeNodesRaised(raised_onto_plane.mesh, straight, 0.22,
                        [](int k) { return k == FindP2Edge(1, 2); });
}

}  // namespace
}  // namespace hapsim::fem
