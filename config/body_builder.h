#pragma once
// Turns the `body` section of a scene into a ready fem::Model, its constant external force and
// its probes. Checks that need the mesh (an empty fixed set, a probe outside the body, a load
// box holding no node) throw InputError at the scene line of the offending key.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "config/scene.h"
#include "fem/model.h"
#include "fem/probe.h"

namespace hapsim::config {

struct BoundProbe {
  std::string name;
  fem::ProbeBinding binding;
};

struct Body {
  fem::Model model;  // with its collision surface, if the scene gives one
  // The surface the viewer draws, carried by the tets; empty: the model's boundary.
  fem::EmbeddedSurface visual_surface;
  Eigen::VectorXd external_force_N;  // (3N) gravity on lumped masses + nodal loads
  std::vector<BoundProbe> probes;
  // Where each deformable object lies in the model, in scene order (one part for one object).
  struct Part {
    int first_node = 0, num_nodes = 0;
    int first_tet = 0, num_tets = 0;
  };
  std::vector<Part> parts;
};

// Builds the mesh (lattice, cut lattice or file), the model, the loads and the probes.
Body MakeBody(const BodyScene& body, const Eigen::Vector3d& gravity_m_s2);

// The scene's deformable objects built as one body (one FEM system, fem::MergeModels; the
// objects' nodes and tets in scene order), or none: a scene of rigid objects builds no FEM.
// Throws InputError at the later object's entry if two deformable objects, or a dynamic rigid
// object and anything, start interpenetrating (over 0.1 mm), naming both and the depth.
std::optional<Body> MakeSceneBody(const Scene& scene);

}  // namespace hapsim::config
