// The surface tree's query before and after issue 9, in one run on one machine: fcl::collide on
// an AABB tree (which copies the whole tree every call) against
// SurfaceBvh::FindIntersectingTriangles (FCL's traversal run on the tree itself). Same tree, same
// shapes, same poses: a 1 cm sphere and a cylinder of the block_press tool (r 2 cm) resting 1 mm
// into the top of the reference blocks.
//
//   build/tests/surface_bvh_benchmark --benchmark_repetitions=5 --benchmark_report_aggregates_only

#include <benchmark/benchmark.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>

#include "contact/surface_bvh.h"
#include "fem/lattice_mesher.h"
#include "tests/contact/surface_bvh_queries.h"

namespace hapsim::contact {
namespace {

struct Block {
  fem::Model body;
  Block(int nx, int nz)
      : body(fem::MakeModel(fem::MakeBoxTetMesh(Eigen::Vector3d::Zero(),
                                                Eigen::Vector3d(0.1, 0.1, 0.05), {nx, nx, nz}),
                            fem::Material{}, {})) {}
};

const Block& GetBlock(int cells) {
  static const Block small(12, 5), large(24, 10);
  return cells == 12 ? small : large;
}

std::unique_ptr<fcl::CollisionGeometryd> MakeShape(int shape) {
  if (shape == 0) return std::make_unique<fcl::Sphered>(0.01);
  return std::make_unique<fcl::Cylinderd>(0.02, 0.04);
}

fcl::Transform3d Pose(int shape) {
  fcl::Transform3d X_WS = fcl::Transform3d::Identity();
  X_WS.translation() = Eigen::Vector3d(0.05, 0.05, shape == 0 ? 0.059 : 0.069);  // 1 mm in
  return X_WS;
}

// args: lattice cells across (12 or 24), shape (0 sphere, 1 cylinder)
void BM_FclCollideCopiesTree(benchmark::State& state) {
  const Block& block = GetBlock(static_cast<int>(state.range(0)));
  const auto tree = MakeReferenceTree<fcl::AABBd>(block.body, block.body.rest_positions_m);
  const auto shape = MakeShape(static_cast<int>(state.range(1)));
  size_t found = 0;
  for (auto _ : state) {
    const std::vector<int> triangles = ReferenceQuery(*tree, *shape, Pose(state.range(1)));
    found = triangles.size();
    benchmark::DoNotOptimize(triangles.data());
  }
  state.counters["triangles"] = static_cast<double>(found);
}

void BM_SurfaceBvhQuery(benchmark::State& state) {
  const Block& block = GetBlock(static_cast<int>(state.range(0)));
  SurfaceBvh bvh(block.body);
  const auto shape = MakeShape(static_cast<int>(state.range(1)));
  std::vector<int> triangles;
  for (auto _ : state) {
    bvh.FindIntersectingTriangles(*shape, Pose(state.range(1)), &triangles);
    benchmark::DoNotOptimize(triangles.data());
  }
  state.counters["triangles"] = static_cast<double>(triangles.size());
}

BENCHMARK(BM_FclCollideCopiesTree)->ArgsProduct({{12, 24}, {0, 1}})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SurfaceBvhQuery)->ArgsProduct({{12, 24}, {0, 1}})->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace hapsim::contact

BENCHMARK_MAIN();
