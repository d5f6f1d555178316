#pragma once
// A triangle surface carried by the tets: the coarse tetrahedral mesh does the mechanics, a finer
// or smoother surface is what the tool touches (collision) or what the eye sees (visual).
//
// Each vertex p of the surface is bound once, at rest, to the tet that contains it by its
// barycentric coordinates w (Σ_a w_a = 1, w_a = 1/4 + b_a·(p − c), b_a the tet's shape
// gradients, c its centroid). It then moves with that tet's linear field:
//   x_p = Σ_a w_a x_{n_a},        so for the whole surface   x_S = B x,
// which is exact for every motion a linear tet represents (rigid motions, uniform strain), and
// a contact at a surface point has the Jacobian row H = Σ_a w_a n ⊗ e_{n_a}: the point's weights
// times its tet's node rows (contact/collision_detection.h). A vertex just outside the mesh (a
// smooth surface over a coarse one bulges out between its nodes) is bound to the nearest tet with
// the same formula, extrapolated (some w_a < 0); it still moves exactly with that tet's field.
//
// In quadratic tets (fem/quadratic_tet.h) the point moves with the tet's quadratic field, on its
// ten nodes: x_p = Σ_a N_a(ξ_p) x_{n_a}, ξ_p the point's reference coordinates, found at rest by
// Newton's method on the isoparametric map X(ξ) = Σ_a N_a(ξ) X_a = p (one step in a straight tet,
// a few in one curved onto the body's surface, fem/curved_boundary.h): exact for every quadratic
// motion, and a contact's Jacobian row carries the quadratic shape functions, as a contact on the
// body's own curved faces does (contact/quadratic_surface.h).
//
// How far outside is too far: a point at distance d outside a tet of edge h has weights beyond
// [0, 1] by ~ d/h, and the tet's rotation and strain reach it through that longer lever, where no
// material constrains it. A smooth surface meshed at the tets' size lies within a small fraction
// of an edge of them (the sagitta h²/8R); a point half the mesh's mean edge length away
// (CalcDefaultMaxOutsideDistance) or more does not belong to that mesh (wrong units, a wrong
// transform, another organ), and EmbedSurface refuses it.

#include <Eigen/Core>
#include <vector>

#include "core/eigen_types.h"
#include "fem/tet_mesh.h"

namespace hapsim::fem {

struct EmbeddedSurface {
  Matrix3Xi triangles;      // (3 x F) vertex indices, outward normals
  Eigen::MatrixXi nodes;    // (k x P) the carrying tet's nodes, k = 4 (linear) or 10 (quadratic)
  Eigen::MatrixXd weights;  // (k x P) their weights (barycentric, or P2 shape functions), Σ = 1
  // (a merge of both kinds pads a linear point's column with its first node at weight 0)

  int nodes_per_point() const { return static_cast<int>(nodes.rows()); }
  int num_points() const { return static_cast<int>(nodes.cols()); }
  int num_triangles() const { return static_cast<int>(triangles.cols()); }
  bool empty() const { return nodes.cols() == 0; }
};

// What EmbedSurface found.
struct EmbeddingReport {
  int num_outside = 0;         // vertices outside every tet, bound to the nearest one
  double max_outside_m = 0.0;  // the farthest of those from its tet, m
  double max_allowed_m = 0.0;  // the limit it was held to, m
};

// Half the mean edge length of the mesh's tets, m: the default limit of EmbedSurface.
double CalcDefaultMaxOutsideDistance(const TetMesh& mesh);

// Binds each vertex of the surface (vertices_m: 3 x P, rest, world, m; triangles: 3 x F over
// them) to its tet. Throws std::invalid_argument if the surface is empty, a triangle's index is
// out of range, or a vertex lies farther than max_outside_m from every tet (the message names
// the vertex, its position and its distance), or (quadratic tets) Newton's method does not find
// its reference coordinates in its curved tet. A spatial grid of the tets' boxes makes it
// O(P · tets per cell).
EmbeddedSurface EmbedSurface(const TetMesh& mesh, const Matrix3Xd& vertices_m,
                             const Matrix3Xi& triangles, double max_outside_m,
                             EmbeddingReport* report = nullptr);

// The body's own boundary (`triangles` over node indices) as an embedded surface: one point per
// node the triangles use, weight 1 on it. What a body without a collision surface contributes
// when merged with one that has one (fem::MergeModels).
EmbeddedSurface MakeNodeSurface(const Matrix3Xi& triangles);

// Several bodies' surfaces side by side, as fem::MergeModels lays out their nodes (body i's from
// first_nodes[i] on). A body whose part is empty contributes its boundary (MakeNodeSurface of
// boundaries[i], node indices of its own), so that every body has a surface in the merge. Empty
// when every part is.
EmbeddedSurface MergeEmbeddedSurfaces(const std::vector<EmbeddedSurface>& parts,
                                      const std::vector<Matrix3Xi>& boundaries,
                                      const std::vector<int>& first_nodes);

// x_points = B x: the surface's points (3P, stacked) at the stacked node positions x_nodes_m
// (3N), world, m. Resizes *x_points_m only when its size differs.
void CalcEmbeddedPositions(const EmbeddedSurface& surface, const Eigen::VectorXd& x_nodes_m,
                           Eigen::VectorXd* x_points_m);

}  // namespace hapsim::fem
