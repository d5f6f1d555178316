#include "contact/surface_bvh.h"

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/math/bv/AABB.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/detail/gjk_solver_libccd.h>
#include <fcl/narrowphase/detail/traversal/collision/mesh_shape_collision_traversal_node.h>
#include <fcl/narrowphase/detail/traversal/collision_node.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/error.h"
#include "core/triangle_overlap.h"

namespace hapsim::contact {
namespace {

template <typename BV>
std::unique_ptr<fcl::BVHModel<BV>> MakeModel(const std::vector<fcl::Vector3d>& vertices,
                                             const std::vector<fcl::Triangle>& triangles) {
  auto model = std::make_unique<fcl::BVHModel<BV>>();
  model->beginModel(static_cast<int>(triangles.size()), static_cast<int>(vertices.size()));
  model->addSubModel(vertices, triangles);
  HAPSIM_INVARIANT(model->endModel() == fcl::BVH_OK);
  return model;
}

template <typename BV>
void RefitModel(const std::vector<int>& surface_nodes, const Eigen::VectorXd& x_m,
                fcl::BVHModel<BV>* model) {
  HAPSIM_INVARIANT(model->beginReplaceModel() == fcl::BVH_OK);
  for (int node : surface_nodes) model->replaceVertex(x_m.segment<3>(3 * node));
  HAPSIM_INVARIANT(model->endReplaceModel(/*refit=*/true, /*bottomup=*/true) == fcl::BVH_OK);
}

// Whether every inner node's children come after it in FCL's node array (FCL's builder appends
// a node's two children after it), so that one pass from the last node to the first refits the
// tree bottom-up (RefitAabbModel).
bool ChildrenFollowParents(const fcl::BVHModel<fcl::AABBd>& model) {
  for (int id = 0; id < model.getNumBVs(); ++id) {
    const fcl::BVNode<fcl::AABBd>& node = model.getBV(id);
    if (!node.isLeaf() && (node.leftChild() <= id || node.rightChild() <= id)) return false;
  }
  return true;
}

// RefitModel's result for an AABB tree, bit for bit (boxes are minima and maxima, exact in any
// order), by one loop over the node array instead of FCL's recursion through its generic fitter:
// block_press's refit (~2,500 nodes) 0.065 → 0.035 ms (docs/BENCHMARKS.md, eighth pass). Needs
// ChildrenFollowParents.
void RefitAabbModel(const std::vector<int>& surface_nodes, const Eigen::VectorXd& x_m,
                    fcl::BVHModel<fcl::AABBd>* model) {
  for (size_t i = 0; i < surface_nodes.size(); ++i)
    model->vertices[i] = x_m.segment<3>(3 * surface_nodes[i]);
  for (int id = model->getNumBVs() - 1; id >= 0; --id) {
    fcl::BVNode<fcl::AABBd>& node = model->getBV(id);
    if (node.isLeaf()) {
      const fcl::Triangle& triangle = model->tri_indices[node.primitiveId()];
      const fcl::Vector3d& a = model->vertices[triangle[0]];
      const fcl::Vector3d& b = model->vertices[triangle[1]];
      const fcl::Vector3d& c = model->vertices[triangle[2]];
      node.bv.min_ = a.cwiseMin(b).cwiseMin(c);
      node.bv.max_ = a.cwiseMax(b).cwiseMax(c);
    } else {
      const fcl::AABBd& left = model->getBV(node.leftChild()).bv;
      const fcl::AABBd& right = model->getBV(node.rightChild()).bv;
      node.bv.min_ = left.min_.cwiseMin(right.min_);
      node.bv.max_ = left.max_.cwiseMax(right.max_);
    }
  }
}

// fcl::collide(BVHModel<AABB>, shape) copies the whole model on every call (FCL 0.7's
// BVHShapeCollider: `new BVHModel<BV>(*obj1)`), because the traversal's initialize() takes the
// model by non-const reference to transform its vertices in place when tf1 is not the identity.
// Ours is in world coordinates (tf1 = identity, so initialize leaves it untouched), and the copy
// was both a cost (the whole surface tree per query) and, under ASan, an alloc-dealloc mismatch
// (allocated in libfcl, freed by the header's delete[]). This runs the same traversal node on the
// model itself, for the sphere and the capsule (a cylinder or a box takes
// CollectOverlappingTriangles below); anything else takes fcl::collide.
template <typename Shape>
void CollideAabbWithShape(fcl::BVHModel<fcl::AABBd>* model, const Shape& shape,
                          const fcl::Transform3d& X_WS, const fcl::CollisionRequestd& request,
                          fcl::CollisionResultd* result) {
  using Solver = fcl::detail::GJKSolver_libccd<double>;  // the request's default gjk_solver_type
  Solver solver;
  fcl::detail::MeshShapeCollisionTraversalNode<fcl::AABBd, Shape, Solver> node;
  fcl::Transform3d X_WW = fcl::Transform3d::Identity();
  HAPSIM_INVARIANT(
      fcl::detail::initialize(node, *model, X_WW, shape, X_WS, &solver, request, *result));
  fcl::detail::collide(&node);
}

// True when it handled the shape's type.
bool CollideAabbWithoutCopy(fcl::BVHModel<fcl::AABBd>* model,
                            const fcl::CollisionGeometry<double>& shape,
                            const fcl::Transform3d& X_WS, const fcl::CollisionRequestd& request,
                            fcl::CollisionResultd* result) {
  switch (shape.getNodeType()) {
    case fcl::GEOM_SPHERE:
      CollideAabbWithShape(model, static_cast<const fcl::Sphered&>(shape), X_WS, request, result);
      return true;
    case fcl::GEOM_CAPSULE:
      CollideAabbWithShape(model, static_cast<const fcl::Capsuled&>(shape), X_WS, request, result);
      return true;
    default:
      return false;
  }
}

// The triangles of an AABB tree that `overlaps` (a, b, c in the shape's frame S) says meet the
// shape, ascending, visiting only the branches whose boxes meet box_W, the shape's world bounding
// box: the walk of FCL's MeshShapeCollisionTraversalNode written out, with an exact test of our
// own at the leaves (one triangle each). *stack is scratch (depth first: one pending sibling per
// level; it grows only on a deeper tree than any before).
template <typename Overlaps>
void CollectOverlappingTriangles(const fcl::BVHModel<fcl::AABBd>& model,
                                 const Eigen::AlignedBox3d& box_W, const Eigen::Isometry3d& X_SW,
                                 const Overlaps& overlaps, std::vector<int>* stack,
                                 std::vector<int>* triangles) {
  const fcl::AABBd shape_box(box_W.min(), box_W.max());
  stack->assign(1, 0);
  while (!stack->empty()) {
    const fcl::BVNode<fcl::AABBd>& node = model.getBV(stack->back());
    stack->pop_back();
    if (!node.bv.overlap(shape_box)) continue;
    if (!node.isLeaf()) {
      stack->push_back(node.rightChild());
      stack->push_back(node.leftChild());
      continue;
    }
    const int t = node.primitiveId();
    const fcl::Triangle& corners = model.tri_indices[t];
    if (overlaps(X_SW * model.vertices[corners[0]], X_SW * model.vertices[corners[1]],
                 X_SW * model.vertices[corners[2]]))
      triangles->push_back(t);
  }
  std::sort(triangles->begin(), triangles->end());
}

}  // namespace

struct SurfaceBvh::Impl {
  std::unique_ptr<fcl::BVHModel<fcl::AABBd>> aabb;
  std::unique_ptr<fcl::BVHModel<fcl::OBBRSSd>> obbrss;
  fcl::CollisionRequestd request;
  fcl::CollisionResultd result;
  std::vector<int> stack;  // CollectOverlappingTriangles' scratch
  int num_triangles = 0;
  bool refit_by_loop = false;  // RefitAabbModel, when ChildrenFollowParents (checked once)
};

SurfaceBvh::SurfaceBvh(const Matrix3Xi& faces, const Eigen::VectorXd& rest_positions_m,
                       SurfaceBvhKind kind)
    : kind_(kind),
      num_body_nodes_(static_cast<int>(rest_positions_m.size() / 3)),
      impl_(std::make_unique<Impl>()) {
  if (faces.cols() == 0) throw std::invalid_argument("SurfaceBvh: body has no surface triangles");
  std::vector<int> local_index(num_body_nodes_, -1);
  for (Eigen::Index f = 0; f < faces.cols(); ++f)
    for (int k = 0; k < 3; ++k) local_index.at(faces(k, f)) = 0;
  for (int n = 0; n < num_body_nodes_; ++n)
    if (local_index[n] == 0) {
      local_index[n] = static_cast<int>(surface_nodes_.size());
      surface_nodes_.push_back(n);
    }
  std::vector<fcl::Vector3d> vertices;
  vertices.reserve(surface_nodes_.size());
  for (int n : surface_nodes_) vertices.push_back(rest_positions_m.segment<3>(3 * n));
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(faces.cols());
  for (Eigen::Index f = 0; f < faces.cols(); ++f)
    triangles.emplace_back(local_index[faces(0, f)], local_index[faces(1, f)],
                           local_index[faces(2, f)]);
  impl_->num_triangles = static_cast<int>(faces.cols());
  if (kind_ == SurfaceBvhKind::kAabb) {
    impl_->aabb = MakeModel<fcl::AABBd>(vertices, triangles);
    impl_->refit_by_loop = ChildrenFollowParents(*impl_->aabb);
  } else {
    impl_->obbrss = MakeModel<fcl::OBBRSSd>(vertices, triangles);
  }
  // Every intersecting triangle is wanted; contact points and depths are not.
  impl_->request.num_max_contacts = static_cast<size_t>(faces.cols());
  impl_->request.enable_contact = false;
}

SurfaceBvh::~SurfaceBvh() = default;

int SurfaceBvh::num_triangles() const { return impl_->num_triangles; }

void SurfaceBvh::Refit(const Eigen::VectorXd& x_m) {
  if (x_m.size() != 3 * num_body_nodes_)
    throw std::invalid_argument("SurfaceBvh::Refit: x_m has " + std::to_string(x_m.size()) +
                                " entries, expected " + std::to_string(3 * num_body_nodes_));
  if (impl_->aabb && impl_->refit_by_loop)
    RefitAabbModel(surface_nodes_, x_m, impl_->aabb.get());
  else if (impl_->aabb)
    RefitModel(surface_nodes_, x_m, impl_->aabb.get());
  else
    RefitModel(surface_nodes_, x_m, impl_->obbrss.get());
}

void SurfaceBvh::FindIntersectingTriangles(const fcl::CollisionGeometry<double>& shape,
                                           const Eigen::Isometry3d& X_WS,
                                           std::vector<int>* triangles) {
  triangles->clear();
  if (impl_->aabb && shape.getNodeType() == fcl::GEOM_CYLINDER) {
    const auto& cylinder = static_cast<const fcl::Cylinderd&>(shape);
    const double r = cylinder.radius, h = 0.5 * cylinder.lz;
    // A cylinder's world box: along world axis i, |a_i| h + r √(1 − a_i²) for its axis a.
    const Eigen::Vector3d axis_W = X_WS.linear().col(2);
    Eigen::Vector3d half_W;
    for (int i = 0; i < 3; ++i)
      half_W[i] =
          std::abs(axis_W[i]) * h + r * std::sqrt(std::max(0.0, 1.0 - axis_W[i] * axis_W[i]));
    const Eigen::AlignedBox3d box_W(X_WS.translation() - half_W, X_WS.translation() + half_W);
    CollectOverlappingTriangles(
        *impl_->aabb, box_W, X_WS.inverse(),
        [r, h](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
          return TriangleOverlapsCylinder(a, b, c, r, h);
        },
        &impl_->stack, triangles);
    return;
  }
  if (impl_->aabb && shape.getNodeType() == fcl::GEOM_BOX) {
    const Eigen::Vector3d half_S = 0.5 * static_cast<const fcl::Boxd&>(shape).side;
    CollectOverlappingTriangles(
        *impl_->aabb, Eigen::AlignedBox3d(-half_S, half_S).transformed(X_WS), X_WS.inverse(),
        [&half_S](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
          return TriangleOverlapsBox(a, b, c, half_S);
        },
        &impl_->stack, triangles);
    return;
  }
  impl_->result.clear();
  const bool done =
      impl_->aabb != nullptr &&
      CollideAabbWithoutCopy(impl_->aabb.get(), shape, X_WS, impl_->request, &impl_->result);
  if (!done) {  // OBBRSS (FCL does not copy oriented trees) or another shape
    const fcl::CollisionGeometryd* body =
        impl_->aabb ? static_cast<const fcl::CollisionGeometryd*>(impl_->aabb.get())
                    : static_cast<const fcl::CollisionGeometryd*>(impl_->obbrss.get());
    fcl::collide(body, fcl::Transform3d::Identity(), &shape, X_WS, impl_->request, impl_->result);
  }
  for (size_t i = 0; i < impl_->result.numContacts(); ++i)
    triangles->push_back(static_cast<int>(impl_->result.getContact(i).b1));
  std::sort(triangles->begin(), triangles->end());
}

}  // namespace hapsim::contact
