#pragma once
// A scene file (YAML, scenes/*.yaml) parsed and validated into plain structs, SI units.
//
// Every error names the file, the 1-based line and the key: an unknown key, a wrong type, an
// out-of-range value (E ≤ 0, ν outside (−1, 0.5), dt ≤ 0, …). Later issues add `tool`,
// `device`, `contact` and `haptic` sections; a scene without `body` builds no FEM.
//
//   name: block_small                  # required, string
//   description: "…"                   # optional
//   gravity_m_s2: [0, 0, -9.81]        # optional, default (0, 0, -9.81)
//   time:
//     dt_s: 0.016666666666666666       # required, > 0
//     num_steps: 200                   # required, ≥ 1
//   body:                              # optional: the deformable body
//     mesh:                            # exactly one of box / ellipsoid / file
//       box: {min_m: [x,y,z], max_m: [x,y,z], cells: [nx,ny,nz]}   # max > min, cells ≥ 1
//       ellipsoid: {center_m: [..], radii_m: [..], cell_size_m: h} # radii > 0, h > 0
//       file: meshes/liver.msh         # .msh (Gmsh 2.2/4.1 ASCII) or .node (TetGen, + .ele),
//                                      # relative to the scene file's folder
//     material:
//       youngs_modulus_Pa: 50000       # > 0
//       poisson_ratio: 0.45            # in (-1, 0.5)
//       density_kg_m3: 1000            # > 0
//       rayleigh_alpha_1_s: 0.0        # ≥ 0, default 0
//       rayleigh_beta_s: 0.0           # ≥ 0, default 0
//     elasticity: corotational         # corotational | linear, default corotational
//     integrator: implicit             # implicit | explicit, default implicit
//     solver: {type: cg, preconditioner: lagged_cholesky, relative_tolerance: 1.0e-6,
//              max_iterations: 1000, refactor_budget_iterations: 50}
//                                      # type cg | cholmod (default cg); preconditioner
//                                      # lagged_cholesky | block_jacobi; tol in (0, 1); iters ≥ 1
//     fixed: {min_m: [..], max_m: [..]}   # optional: nodes inside this box are fixed
//     loads:                           # optional: total force spread evenly over the nodes in a
//     box
//       - {min_m: [..], max_m: [..], total_force_N: [fx, fy, fz]}
//     probes:                          # optional: points whose displacement is reported
//       - {name: top_center, position_m: [0, 0, 0.05]}

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "fem/fem_options.h"
#include "fem/material.h"

namespace hapsim::config {

// Where a value came from, so checks made after meshing (an empty fixed set, a probe outside the
// body) can still name the file and line.
struct SourceLocation {
  std::string file;
  int line = 0;  // 1-based
  std::string key;
};

struct AxisAlignedBox {
  Eigen::Vector3d min_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d max_m = Eigen::Vector3d::Zero();
  bool Contains(const Eigen::Vector3d& p_m, double tolerance_m) const {
    return ((p_m.array() >= min_m.array() - tolerance_m) &&
            (p_m.array() <= max_m.array() + tolerance_m))
        .all();
  }
};

struct MeshSource {
  enum class Kind { kBox, kEllipsoid, kFile };
  Kind kind = Kind::kBox;
  AxisAlignedBox box;                                  // kBox
  Eigen::Vector3i cells = Eigen::Vector3i::Ones();     // kBox: lattice cells per axis
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();  // kEllipsoid
  Eigen::Vector3d radii_m = Eigen::Vector3d::Ones();   // kEllipsoid
  double cell_size_m = 0.0;                            // kEllipsoid: lattice cell edge
  std::string file;  // kFile: path resolved against the scene file's folder
  SourceLocation location;
};

struct NodalLoad {
  AxisAlignedBox region;
  Eigen::Vector3d total_force_N = Eigen::Vector3d::Zero();
  SourceLocation location;
};

struct Probe {
  std::string name;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  SourceLocation location;
};

struct BodyScene {
  MeshSource mesh;
  fem::Material material;
  fem::FemOptions options;
  std::optional<AxisAlignedBox> fixed;
  SourceLocation fixed_location;
  std::vector<NodalLoad> loads;
  std::vector<Probe> probes;
};

struct Scene {
  std::string file;  // the path it was loaded from
  std::string name;
  std::string description;
  Eigen::Vector3d gravity_m_s2{0.0, 0.0, -9.81};
  double dt_s = 0.0;
  int num_steps = 0;
  std::optional<BodyScene> body;
};

// Loads and validates a scene file. Throws hapsim::InputError naming file, line and key.
Scene LoadScene(const std::string& path);

// Same, from YAML text; `file_label` names it in errors and `base_dir` resolves mesh files.
Scene ParseScene(const std::string& yaml_text, const std::string& file_label,
                 const std::string& base_dir);

}  // namespace hapsim::config
