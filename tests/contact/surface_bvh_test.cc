// SurfaceBvh::FindIntersectingTriangles runs FCL's traversal on the tree itself instead of
// fcl::collide, which copies the tree per call (issue 9). Checked against fcl::collide on an
// identical tree, for every tool primitive, at random poses over a deformed, refitted surface.

#include "contact/surface_bvh.h"

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "fem/lattice_mesher.h"
#include "tests/contact/surface_bvh_queries.h"

namespace hapsim::contact {
namespace {

TEST(SurfaceBvh, FindsExactlyTheTrianglesOfFclCollide) {
  const fem::Model body = fem::MakeModel(
      fem::MakeBoxTetMesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.1, 0.1, 0.05), {12, 12, 5}),
      fem::Material{}, {});
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  // A dented top (so the refit matters): nodes pushed down by up to 3 mm.
  Eigen::VectorXd x_m = body.rest_positions_m;
  for (int n = 0; n < body.num_nodes(); ++n)
    if (x_m[3 * n + 2] > 0.049) x_m[3 * n + 2] -= 0.003 * (0.5 + 0.5 * unit(random));
  SurfaceBvh bvh(body);
  bvh.Refit(x_m);
  const auto reference = MakeReferenceTree(body, x_m);
  const fcl::Sphered sphere(0.01);
  const fcl::Capsuled capsule(0.005, 0.04);
  const fcl::Cylinderd cylinder(0.02, 0.04);
  const fcl::Boxd box(0.03, 0.02, 0.04);
  const fcl::CollisionGeometryd* shapes[] = {&sphere, &capsule, &cylinder, &box};
  int found = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::Isometry3d X_WS = Eigen::Isometry3d::Identity();
    X_WS.linear() =
        Eigen::Quaterniond(Eigen::Vector4d(unit(random), unit(random), unit(random), unit(random)))
            .normalized()
            .toRotationMatrix();
    X_WS.translation() = Eigen::Vector3d(0.05 + 0.06 * unit(random), 0.05 + 0.06 * unit(random),
                                         0.05 + 0.02 * unit(random));
    for (const fcl::CollisionGeometryd* shape : shapes) {
      std::vector<int> triangles;
      bvh.FindIntersectingTriangles(*shape, X_WS, &triangles);
      EXPECT_EQ(triangles, ReferenceQuery(*reference, *shape, X_WS)) << "trial " << trial;
      found += static_cast<int>(triangles.size());
    }
  }
  EXPECT_GT(found, 1000);  // the poses do reach the surface
}

}  // namespace
}  // namespace hapsim::contact
