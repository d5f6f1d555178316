#pragma once
// A tetrahedral mesh: rest node positions and tetrahedra, linear (4 nodes) or quadratic (10 nodes:
// the 4 corners and a node on each edge, fem/quadratic_tet.h). Plain data, built by the lattice
// mesher or read from Gmsh/TetGen files; fem::Model is built from it.

#include <Eigen/Core>
#include <optional>
#include <string>

#include "core/eigen_types.h"

namespace hapsim::fem {

struct TetMesh {
  Matrix3Xd rest_positions_m;  // (3 x num_nodes) rest node positions, world frame, m
  Matrix4Xi tets;              // (4 x num_tets) node indices; positively oriented: V > 0 below
  // Quadratic tets only: (6 x num_tets) the node on each edge, in kP2EdgeCorners' order
  // (fem/quadratic_tet.h: (0,1) (1,2) (2,0) (3,0) (3,2) (3,1) of `tets`). Empty: linear tets.
  // Edge nodes are nodes like the corners (any index); the corners alone make the linear tets that
  // the element rotations, the BVH cells and the surface binding use.
  Matrix6Xi edge_nodes;

  int num_nodes() const { return static_cast<int>(rest_positions_m.cols()); }
  int num_tets() const { return static_cast<int>(tets.cols()); }
  bool is_quadratic() const { return edge_nodes.cols() > 0; }
  int nodes_per_tet() const { return is_quadratic() ? 10 : 4; }
  // Node a (0..nodes_per_tet() − 1) of tet t: a corner for a < 4, else edge node a − 4.
  int node(int a, int t) const { return a < 4 ? tets(a, t) : edge_nodes(a - 4, t); }
};

// Signed volume V = (p1−p0)·((p2−p0)×(p3−p0)) / 6, m³. Positive for a right-handed tet.
double CalcSignedVolume(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                        const Eigen::Vector3d& p2, const Eigen::Vector3d& p3);

// Signed volume of tet t of `mesh` at positions `p_m` (3 x num_nodes).
double CalcSignedVolume(const Matrix3Xd& p_m, const Eigen::Vector4i& tet);

// Scale-free quality of a tet: 6√2 V / ℓ_rms³, 1 for a regular tet, ≤ 0 when inverted or flat.
double CalcTetQuality(const Matrix3Xd& p_m, const Eigen::Vector4i& tet);

// What a mesher's output is judged by (fem/surface_mesher.h, `hapsim mesh`): the extreme
// dihedral angles over all tets (between the two faces at each of a tet's six edges; a regular
// tet has 70.53° at every edge, a sliver near 0° and 180°) and the total volume.
struct TetMeshQuality {
  int num_tets = 0;
  double min_dihedral_deg = 0.0;
  double max_dihedral_deg = 0.0;
  double volume_m3 = 0.0;
};
TetMeshQuality CalcTetMeshQuality(const TetMesh& mesh);

// Tets whose quality is at most this are degenerate (flat to round-off, or a sliver no solver
// can use). A lattice tet has quality ≈ 0.6–0.8; a mesh generator's worst slivers ≈ 1e-3.
constexpr double kDegenerateTetQuality = 1e-6;

// Describes the first problem that makes `mesh` unusable as a rest mesh (node index out of
// range, a node used twice in one tet, a degenerate or inverted tet), or nullopt if none.
// *bad_tet, if given, receives the index of the offending tet.
std::optional<std::string> FindRestMeshProblem(const TetMesh& mesh, int* bad_tet = nullptr);

// Boundary faces (faces used by exactly one tet), each oriented so that its normal
// (q1−q0)×(q2−q0) points out of the body. Returns (3 x num_faces) node indices. A quadratic
// mesh's boundary face is returned as its four sub-triangles through its edge nodes (corner,
// edge, edge ×3 and the middle one), which the detector and the viewer use as any triangles.
Matrix3Xi ExtractBoundarySurface(const TetMesh& mesh);

// The quadratic mesh of a linear one: a node added at the midpoint of every edge (shared by the
// tets around it), numbered after the linear mesh's nodes in order of first appearance.
TetMesh MakeQuadraticMesh(const TetMesh& linear);

}  // namespace hapsim::fem
