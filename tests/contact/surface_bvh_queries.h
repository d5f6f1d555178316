#pragma once
// The surface tree's query checked against FCL's own fcl::collide on a tree over the same
// triangles: the second method for tests/contact/surface_bvh_test.cc (an OBBRSS tree: another
// bounding volume and traversal, and one fcl::collide does not copy) and the "before" of
// tests/bench/surface_bvh_benchmark.cc (an AABB tree, which fcl::collide copies on every call and
// SurfaceBvh::FindIntersectingTriangles does not).
//
// Under ASan the AABB copy is an alloc-dealloc mismatch inside FCL (Debian's libfcl allocates the
// copy with Eigen's aligned malloc, the header's destructor in our binary frees it with delete[]),
// so only the benchmark, never built with sanitizers, uses it.

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/AABB.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>

#include <Eigen/Core>
#include <algorithm>
#include <memory>
#include <vector>

#include "fem/model.h"

namespace hapsim::contact {

// A tree of bounding volumes BV (fcl::AABBd, fcl::OBBRSSd) over body's surface triangles at x_m
// (3N), indexed like body.surface_triangles.
template <typename BV>
std::unique_ptr<fcl::BVHModel<BV>> MakeReferenceTree(const fem::Model& body,
                                                     const Eigen::VectorXd& x_m) {
  // The surface nodes only, as SurfaceBvh holds them (a copy of the tree costs per vertex too).
  const Matrix3Xi& faces = body.surface_triangles;
  std::vector<int> local(body.num_nodes(), -1);
  std::vector<fcl::Vector3d> vertices;
  for (Eigen::Index f = 0; f < faces.cols(); ++f)
    for (int k = 0; k < 3; ++k)
      if (local[faces(k, f)] < 0) {
        local[faces(k, f)] = static_cast<int>(vertices.size());
        vertices.push_back(x_m.segment<3>(3 * faces(k, f)));
      }
  std::vector<fcl::Triangle> triangles;
  for (Eigen::Index f = 0; f < faces.cols(); ++f)
    triangles.emplace_back(local[faces(0, f)], local[faces(1, f)], local[faces(2, f)]);
  auto model = std::make_unique<fcl::BVHModel<BV>>();
  model->beginModel(static_cast<int>(triangles.size()), static_cast<int>(vertices.size()));
  model->addSubModel(vertices, triangles);
  model->endModel();
  return model;
}

// The triangles fcl::collide finds between `tree` and `shape` at X_WS, sorted.
template <typename BV>
std::vector<int> ReferenceQuery(const fcl::BVHModel<BV>& tree, const fcl::CollisionGeometryd& shape,
                                const fcl::Transform3d& X_WS) {
  fcl::CollisionRequestd request(static_cast<size_t>(tree.num_tris), false);
  fcl::CollisionResultd result;
  fcl::collide(&tree, fcl::Transform3d::Identity(), &shape, X_WS, request, result);
  std::vector<int> triangles;
  for (size_t i = 0; i < result.numContacts(); ++i)
    triangles.push_back(static_cast<int>(result.getContact(i).b1));
  std::sort(triangles.begin(), triangles.end());
  return triangles;
}

}  // namespace hapsim::contact
