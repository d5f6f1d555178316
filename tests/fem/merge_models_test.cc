// Several deformable objects as one FEM system (fem::MergeModels): a soft and a stiff block side
// by side, each clamped at its base and sagging under gravity, stepped together must move exactly
// as each stepped alone (a second computation of the same physics: the merged matrices are block
// diagonal), with each tet keeping its own material; the merged mass is the sum of ρV.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "fem/lattice_mesher.h"
#include "fem/model.h"
#include "fem/time_stepper.h"

namespace hapsim::fem {
namespace {

constexpr double kGravity_m_s2 = 9.81;

// A 4 × 1 × 1 cm bar along x, clamped at x = x0 (a cantilever: it sags under its weight).
Model MakeBar(double x0_m, double youngs_modulus_Pa, double density_kg_m3) {
  const TetMesh mesh =
      MakeBoxTetMesh({x0_m, 0.0, 0.0}, {x0_m + 0.04, 0.01, 0.01}, Eigen::Vector3i(8, 2, 2));
  Material material;
  material.youngs_modulus_Pa = youngs_modulus_Pa;
  material.poisson_ratio = 0.3;
  material.density_kg_m3 = density_kg_m3;
  material.rayleigh_alpha_1_s = 2.0;
  material.rayleigh_beta_s = 0.001;
  return MakeModel(mesh, material, FindNodesInBox(mesh, {x0_m, -1, -1}, {x0_m, 1, 1}, 1e-9));
}

FemOptions Direct() {
  FemOptions options;
  options.solver.kind = SolverKind::kCholmod;  // exact solves: the comparison is not of tolerances
  return options;
}

// The state after `steps` implicit steps of 10 ms from rest under gravity.
State Sag(const Model& model, int steps) {
  TimeStepper stepper(model, Direct(), 0.01, CalcGravityForce(model, {0, 0, -kGravity_m_s2}));
  State state = MakeRestState(model);
  for (int k = 0; k < steps; ++k) stepper.Step(&state);
  return state;
}

TEST(MergeModels, TwoBarsSteppedTogetherMoveAsEachSteppedAlone) {
  const Model soft = MakeBar(0.0, 20e3, 1000.0);
  const Model stiff = MakeBar(0.1, 200e3, 1500.0);
  const Model merged = MergeModels({soft, stiff});
  ASSERT_EQ(merged.num_nodes(), soft.num_nodes() + stiff.num_nodes());
  ASSERT_EQ(merged.num_tets(), soft.num_tets() + stiff.num_tets());
  EXPECT_EQ(merged.num_fixed_nodes(), soft.num_fixed_nodes() + stiff.num_fixed_nodes());
  // The objects' node ranges, one after the other; a lone model is one object of all its nodes.
  ASSERT_EQ(merged.num_objects(), 2);
  EXPECT_EQ(merged.object_first_node(0), 0);
  EXPECT_EQ(merged.object_end_node(0), soft.num_nodes());
  EXPECT_EQ(merged.object_first_node(1), soft.num_nodes());
  EXPECT_EQ(merged.object_end_node(1), merged.num_nodes());
  EXPECT_EQ(soft.num_objects(), 1);
  EXPECT_EQ(soft.object_end_node(0), soft.num_nodes());
  EXPECT_EQ(merged.surface_triangles.cols(),
            soft.surface_triangles.cols() + stiff.surface_triangles.cols());
  // Mass: ρ V of each bar (4 cm³), whatever the mesh.
  EXPECT_NEAR(merged.node_mass_kg.sum(), (1000.0 + 1500.0) * 4e-6, 1e-12);

  const int steps = 50;
  const State together = Sag(merged, steps);
  const State alone_soft = Sag(soft, steps), alone_stiff = Sag(stiff, steps);
  const Eigen::Index n_soft = soft.num_dofs();
  const double tip_soft_m = (together.x_m.head(n_soft) - soft.rest_positions_m).minCoeff();
  const double tip_stiff_m =
      (together.x_m.tail(stiff.num_dofs()) - stiff.rest_positions_m).minCoeff();
  std::printf("two bars in one system: lowest displacement %.6e m (20 kPa), %.6e m (200 kPa)\n",
              tip_soft_m, tip_stiff_m);
  EXPECT_LT((together.x_m.head(n_soft) - alone_soft.x_m).lpNorm<Eigen::Infinity>(),
            1e-9 * std::abs(tip_soft_m));
  EXPECT_LT((together.x_m.tail(stiff.num_dofs()) - alone_stiff.x_m).lpNorm<Eigen::Infinity>(),
            1e-9 * std::abs(tip_stiff_m));
  // Each kept its own material: the stiff bar sags far less (and not the soft bar's amount).
  EXPECT_LT(std::abs(tip_stiff_m), 0.5 * std::abs(tip_soft_m));
}

TEST(MergeModels, RefusesDifferentDamping) {
  Model other = MakeBar(0.1, 200e3, 1500.0);
  other.material.rayleigh_beta_s = 0.002;
  EXPECT_THROW(MergeModels({MakeBar(0.0, 20e3, 1000.0), other}), std::invalid_argument);
  EXPECT_THROW(MergeModels({}), std::invalid_argument);
}

}  // namespace
}  // namespace hapsim::fem
