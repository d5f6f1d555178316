#pragma once
// What the rigid-object tests share (rigid_objects_test.cc, moving_objects_test.cc,
// object_dynamics_test.cc, body_body_contact_test.cc): a free soft block to rest on a plate, the
// force the rigid objects put on a body, and a sphere tool.

#include <Eigen/Core>

#include "contact/visual_frame.h"
#include "fem/lattice_mesher.h"
#include "fem/model.h"
#include "fem/time_stepper.h"

namespace hapsim::contact::fixtures {

constexpr double kGravity_m_s2 = 9.81;

// A sphere tool of the given radius and mass.
inline ToolModel MakeSphereTool(double radius_m, double mass_kg) {
  ToolShape sphere;
  sphere.kind = ToolShape::Kind::kSphere;
  sphere.radius_m = radius_m;
  return MakeToolModelWithMass(sphere, mass_kg);
}

// A free 4 x 4 x 2 cm soft block (no fixed node, E 50 kPa) standing on z = 0, its gravity load
// and its mass ρ V (independent of the mesh).
struct FreeBlock {
  fem::Model model;
  Eigen::VectorXd gravity_N;
  double mass_kg = 0.0;
};

inline FreeBlock MakeFreeBlock() {
  const fem::TetMesh mesh = fem::MakeBoxTetMesh({-0.02, -0.02, 0.0}, {0.02, 0.02, 0.02}, {4, 4, 2});
  fem::Material material;
  material.youngs_modulus_Pa = 50e3;
  material.poisson_ratio = 0.45;
  material.density_kg_m3 = 1000.0;
  material.rayleigh_alpha_1_s = 5.0;  // settles the block within the runs
  FreeBlock block{fem::MakeModel(mesh, material, {}), {}, 0.0};
  block.gravity_N = fem::CalcGravityForce(block.model, {0, 0, -kGravity_m_s2});
  block.mass_kg = material.density_kg_m3 * 0.04 * 0.04 * 0.02;
  return block;
}

// Sum of λ over the rows of contacts that touch no tool: the force the rigid objects put on the
// body, along their normals, N.
inline double CalcObjectForceOnBody_N(const VisualFrame& frame) {
  double total_N = 0.0;
  for (size_t i = 0; i < frame.contacts().size(); ++i)
    if (!frame.contacts()[i].on_tool) total_N += frame.impulses()[static_cast<Eigen::Index>(i)];
  return total_N;
}

}  // namespace hapsim::contact::fixtures
