#pragma once
// Bounding-volume hierarchy (FCL BVHModel) over the deformable body's boundary triangles: built
// once from the rest positions, then refitted every frame from the new node positions (the tree
// topology is kept; only the bounding volumes are recomputed bottom-up).
//
// Refit uses FCL's beginReplaceModel / replaceVertex / endReplaceModel(refit = true), not
// beginUpdateModel: the "update" path keeps the previous frame's vertices and fits each leaf
// around both frames (a swept volume for FCL's own continuous query), which loosens every box.
//
// BV type: both AABB and OBBRSS are available; AABB is the default. Measured (Release, one core)
// on the reference blocks of DESIGN.md §7, a 1 cm sphere / 2 cm cube near the top centre,
// inflated by 1 mm … 2 cm (15–101 and 38–356 faces found):
//                               build     refit    sphere query                 box query
//   12×12×5  (1,056 faces) AABB  0.6 ms   0.05 ms  0.014–0.022 ms               0.02–0.06 ms
//                        OBBRSS  2.2 ms   0.87 ms  0.020–0.056 ms               0.04–0.14 ms
//   24×24×10 (4,224 faces) AABB  2.5 ms   0.17 ms  0.050–0.083 ms               0.08–0.22 ms
//                        OBBRSS  9.0 ms   3.9 ms   0.042–0.160 ms               0.09–0.47 ms
// OBBRSS's refit re-fits an oriented box per node (covariance + eigen-decomposition), 20x the
// AABB refit, and its tighter volumes do not pay off for compact tools on a near-flat surface.
// For a non-oriented BV (AABB), FCL 0.7's collide() copies the whole BVHModel on every call
// (BVHShapeCollider); FindIntersectingTriangles runs FCL's traversal node on the tree itself
// instead (surface_bvh.cc). Measured in one run (tests/bench/surface_bvh_benchmark, CPU-time
// medians, AMD EPYC VM, 2026-11-24; the table above predates it): 1 cm sphere 16.1 -> 4.0 us
// (12x12x5) and 54.7 -> 9.2 us (24x24x10); the block_press cylinder 1 mm in 49.1 -> 35.8 us and
// 149 -> 96 us. The same triangles as fcl::collide (tests/contact/surface_bvh_test.cc).
// FCL tests each leaf triangle against a cylinder or box by GJK on libccd, ~1 us a triangle; the
// clipping tests of core/triangle_overlap.h take the block_press cylinder query to 19 us on the
// 24x24x10 block (Intel Xeon VM, 2026-11-28), and block_press's broad phase, frames with ≥ 200
// contacts, from 0.20 to 0.05 ms, with the same contacts bit for bit.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "core/eigen_types.h"
#include "fem/model.h"

namespace fcl {
template <typename S>
class CollisionGeometry;
}  // namespace fcl

namespace hapsim::contact {

enum class SurfaceBvhKind { kAabb, kObbrss };

class SurfaceBvh {
 public:
  // Builds the tree over `triangles` (3 x F, indices of points) at the points' stacked rest
  // positions rest_positions_m (3P, m). Throws std::invalid_argument if there are no triangles.
  SurfaceBvh(const Matrix3Xi& triangles, const Eigen::VectorXd& rest_positions_m,
             SurfaceBvhKind kind = SurfaceBvhKind::kAabb);
  // Over the body's boundary, body.surface_triangles at body.rest_positions_m.
  explicit SurfaceBvh(const fem::Model& body, SurfaceBvhKind kind = SurfaceBvhKind::kAabb)
      : SurfaceBvh(body.surface_triangles, body.rest_positions_m, kind) {}
  ~SurfaceBvh();
  SurfaceBvh(const SurfaceBvh&) = delete;
  SurfaceBvh& operator=(const SurfaceBvh&) = delete;

  // Refits the bounding volumes to the stacked node positions x_m (3N, world, m).
  // Precondition: x_m.size() == 3 × the body's node count (checked, throws std::invalid_argument).
  void Refit(const Eigen::VectorXd& x_m);

  // Clears *triangles and fills it with the indices (columns of body.surface_triangles) of the
  // triangles that intersect `shape` placed at X_WS, at the last refitted positions, ascending.
  // On an AABB tree a cylinder or a box is tested by clipping (core/triangle_overlap.h); the
  // other shapes, and every shape on an OBBRSS tree, by FCL's triangle-versus-shape test (collide
  // with num_max_contacts = every triangle).
  void FindIntersectingTriangles(const fcl::CollisionGeometry<double>& shape,
                                 const Eigen::Isometry3d& X_WS, std::vector<int>* triangles);

  SurfaceBvhKind kind() const { return kind_; }
  int num_triangles() const;
  // Body nodes used by the surface triangles, ascending.
  const std::vector<int>& surface_nodes() const { return surface_nodes_; }

 private:
  struct Impl;
  SurfaceBvhKind kind_;
  int num_body_nodes_ = 0;
  std::vector<int> surface_nodes_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hapsim::contact
