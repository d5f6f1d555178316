#pragma once
// A scene file (YAML, scenes/*.yaml) parsed and validated into plain structs, SI units.
//
// Every error names the file, the 1-based line and the key: an unknown key, a wrong type, an
// out-of-range value (E ≤ 0, ν outside (−1, 0.5), dt ≤ 0, …). A scene without `body` builds no
// FEM; a scene without `tool` has no tool, coupling, contact, haptic or device. An error inside
// a tool mesh file names that file and its line.
//
//   name: block_small                  # required, string
//   description: "…"                   # optional
//   gravity_m_s2: [0, 0, -9.81]        # optional, default (0, 0, -9.81)
//   time:
//     dt_s: 0.016666666666666666       # required, > 0 (the visual frame)
//     num_steps: 200                   # required, ≥ 1
//   body:                              # optional: the deformable body
//     mesh:                            # exactly one of box / ellipsoid / file / surface
//       box: {min_m: [x,y,z], max_m: [x,y,z], cells: [nx,ny,nz]}   # max > min, cells ≥ 1
//         # optional in box: graded: {focus_m: [x,y,z], ratio: 5}: cells grow linearly with the
//         # distance from focus_m (inside the box) to `ratio` (≥ 1) times at the farthest face;
//         # in graded, circle_radius_m: 0.003 (> 0) bends the lattice into an O-grid about the
//         # vertical through the focus, a ring of nodes on that circle (a punch's rim;
//         # fem::MakeGradedBoxTetMesh; the focus at the box's centre in x and y, cells in x and
//         # y equal and even)
//       ellipsoid: {center_m: [..], radii_m: [..], cell_size_m: h} # radii > 0, h > 0
//       file: meshes/liver.msh         # .msh (Gmsh, any version), .node (TetGen, + .ele) or .vtk
//                                      # (legacy VTK unstructured grid, ASCII or binary),
//                                      # relative to the scene file's folder
//       surface: meshes/liver.obj      # a closed OBJ/STL surface in metres, filled with tets at
//       cell_size_m: 0.008             # load (fem/surface_mesher.h; cached: config/
//                                      # surface_mesh_cache.h); h > 0, with surface only
//       refine: {near_m: [x,y,z], cell_size_m: 0.004, radius_m: 0.02}   # optional, with
//                                      # surface: finer cells within radius_m of near_m
//       units: mm                      # optional, with file or surface: mm | cm | m (default)
//       transform: {scale: 1, rotation_vector_rad: [..], translation_m: [..]}   # optional, with
//                                      # file or surface: p' = R (units · scale · p) + t, scale > 0
//                                      # (cell_size_m and refine are in metres, after it)
//     collision: {file: meshes/liver_fine.obj}   # optional: a closed OBJ/STL surface carried by
//                                      # the tets (fem/surface_embedding.h), on which the tool's
//                                      # contacts are found instead of the tets' own boundary;
//                                      # units and transform as the mesh's (not inherited). A
//                                      # vertex farther than half the tets' mean edge from every
//                                      # tet is an error. Contacts with rigid objects and the
//                                      # godobject mode stay on the boundary.
//     visual: {file: meshes/liver_fine.obj}      # optional: a closed surface the viewer draws,
//                                      # carried the same way; default: the tets' boundary
//     material:
//       youngs_modulus_Pa: 50000       # > 0
//       poisson_ratio: 0.45            # in (-1, 0.5)
//       density_kg_m3: 1000            # > 0
//       rayleigh_alpha_1_s: 0.0        # ≥ 0, default 0
//       rayleigh_beta_s: 0.0           # ≥ 0, default 0
//     elasticity: corotational         # corotational | linear, default corotational
//     integrator: implicit             # implicit | explicit, default implicit
//     solver: {type: cg, preconditioner: lagged_cholesky, relative_tolerance: 1.0e-6,
//              max_iterations: 1000, refactor_budget_iterations: 50, factor_precision: single}
//                                      # type cg | cholmod (default cg); preconditioner
//                                      # lagged_cholesky | block_jacobi; tol in (0, 1); iters ≥ 1;
//                                      # factor_precision single | double | half
//                                      # (lagged_cholesky's; fem/fem_options.h says which when)
//     fixed: {min_m: [..], max_m: [..]}   # optional: nodes inside this box are fixed
//     loads:                           # optional: each total force spread evenly over the
//                                      # nodes in its box
//       - {min_m: [..], max_m: [..], total_force_N: [fx, fy, fz]}
//     probes:                          # optional: points whose displacement is reported
//       - {name: top_center, position_m: [0, 0, 0.05]}
//   objects:                           # optional: the scene's objects (DESIGN.md §9), each
//                                      # exactly one of deformable / rigid
//     - name: tray                     # required, unique among the objects
//       rigid:                         # a rigid object: builds no FEM; needs a tool (its
//                                      # contacts are solved in the visual frame) and the
//                                      # unilateral or friction law (not equality)
//         shape: {box: {half_extents_m: [0.1, 0.1, 0.005]}}   # as tool.shape (a mesh file:
//                                      # closed OBJ/STL in metres, kept in its own frame)
//         position_m: [0, 0, -0.005]   # origin of the shape's frame, world; default 0
//         rotation_vector_rad: [0, 0, 0]   # default 0
//         trajectory:                  # optional, instead of position_m / rotation_vector_rad:
//           - {t_s: 0, position_m: [..], rotation_vector_rad: [..]}   # moved by a script, as
//                                      # device.trajectory (without button)
//         grabbable: false             # true: touching it with the tool selects it, the device
//                                      # button grabs it (paper 003); not with a trajectory
//         dynamic: false               # true: it falls under gravity, rests on the tissue and
//                                      # the other objects, is pushed by the tool, and falls
//                                      # when let go (contact/object_dynamics.h); not with a
//                                      # trajectory. Needs exactly one of:
//         mass_kg: 0.01                #   its mass (> 0), or
//         density_kg_m3: 7800          #   its density (> 0); only a dynamic object has either.
//                                      # A dynamic mesh is re-centred on its centre of mass.
//         friction_coefficient: 0.1    # optional, ≥ 0: μ of every contact with it (friction law
//                                      # only); default contact.friction_coefficient
//         material: {stiffness: 1, viscosity: 0, stickiness_N: 0, friction_N_m: 0}
//                                      # optional, the material mode's (paper 003; defaults as
//                                      # shown): stiffness, viscosity in [0, 1] (fractions of
//                                      # haptic.material's max), stickiness ≥ 0, friction ≥ 0
//     - name: liver
//       deformable: {mesh: …, material: …}   # the keys of `body`; `body` is the shorthand for
//                                      # one deformable object named "body" (the first). Several
//                                      # deformable objects are solved as one FEM system: the
//                                      # later ones take the first one's elasticity, integrator
//                                      # and solver (giving them is an error) and must share its
//                                      # Rayleigh damping; each has its own mesh, E, ν, density,
//                                      # fixed region, loads and probes. They touch each other
//                                      # (contact/body_body_contacts.h; not themselves where
//                                      # they fold), and must not start interpenetrating.
//   tool:                              # optional: the rigid tool (DESIGN.md §3); needs coupling
//                                      # and device
//     shape:                           # exactly one of (tool frame T: origin at the COM, z the
//                                      # axis of a capsule or cylinder):
//       sphere: {radius_m: 0.01}                        # > 0
//       capsule: {radius_m: 0.005, length_m: 0.05}      # radius > 0, length ≥ 0 (cap centres)
//       cylinder: {radius_m: 0.01, length_m: 0.06}      # > 0 each (full height); optional
//                                      # edge_radius_m: rounded rim, in [0, min(r, length/2)],
//                                      # default 0 (sharp)
//       box: {half_extents_m: [0.01, 0.01, 0.02]}       # > 0 each
//       mesh: {file: tools/probe.stl}  # closed OBJ/STL in metres, relative to the scene file's
//                                      # folder; re-centred on its centre of mass
//       point: {radius_m: 0.001}       # > 0: a 3-DOF point, the god-object's proxy of that
//                                      # radius (haptic.mode godobject); elsewhere a sphere
//     mass_kg: 0.05                    # exactly one of mass_kg / density_kg_m3, > 0
//     position_m: [0, 0, 0.09]         # initial centre of mass, world; default 0
//     rotation_vector_rad: [0, 0, 0]   # initial orientation q_WT = exp(axis · angle); default 0
//     grasp:                           # optional: the tool is a grasper (contact/tissue_grasp.h);
//                                      # the device's button closes its jaws on the body's surface
//                                      # points inside them and opens them again. Needs a body,
//                                      # normal rows (contact.law unilateral or equality), no
//                                      # `collision:` surface, and a mode that renders the
//                                      # frame's rows or coupling (hybrid, linear, lcp, coupling,
//                                      # reference)
//       jaw_center_m: [0, 0, -0.01]    # the jaws: a ball in the tool frame, centre, m
//       jaw_radius_m: 0.004            # and radius, m (> 0)
//       max_force_N: 3                 # grip force per held point past which it slips, N (> 0);
//                                      # default: never slips
//   coupling:                          # required with a tool: the virtual coupling, ≥ 0 each
//     {k_lin_N_m: 2000, b_lin_N_s_m: 5, k_ang_N_m_rad: 2, b_ang_N_m_s_rad: 0.01}
//   contact:                           # optional (with a tool), defaults as shown
//     law: unilateral                  # equality | unilateral | friction
//     friction_coefficient: 0.3        # ≥ 0; required with friction, an error with other laws
//     stabilization_beta: 0.2          # in [0, 1]: fraction of a penetration undone per frame
//     restitution: 0.0                 # in [0, 1]
//     margin_m: 0.001                  # ≥ 0: contacts are detected up to this gap
//     tool_features: true              # false: only the body's nodes (or collision-surface
//                                      # points) touch the tool, and a sphere's centre the faces:
//                                      # no contact where a tool corner, rim point or sharp edge
//                                      # presses a face between nodes (node-to-surface contact,
//                                      # the FE convention for a rigid indenter; a tool narrower
//                                      # than a face then cuts in)
//     compliance: warped               # warped | exact: the body's contact compliance
//                                      # (contact/visual_frame.h ComplianceMethod)
//     model_compliance_step: auto      # visual | haptic | auto: the step the linear contact
//                                      # model's body compliance is for (ModelComplianceStep);
//                                      # auto: the haptic step's in the hybrid mode below
//                                      # 100 Hz, else the visual step's (the paper's)
//   haptic:                            # optional (with a tool), defaults as shown
//     rate_hz: 1000                    # > 0; rate_hz · dt_s must be an integer ≥ 1 (to 1e-9):
//                                      # the number of haptic steps per visual frame
//     mode: hybrid                     # hybrid | linear | lcp | coupling | reference |
//                                      # penalty | material | impact | godobject
//                                      # (device/haptic_mode.h; hybrid: the paper's linear
//                                      # model with the frame's other candidate rows switched
//                                      # on at 1 kHz, so a fast tool cannot tunnel; linear: the
//                                      # paper's model alone; godobject: a point tool only;
//                                      # reference: `hapsim sim` only)
//     penalty:                         # optional, penalty mode (contact/penalty_contact.h)
//       {stiffness_N_m: 600, predictive_margin: true, max_force_change_N: 0.5,
//        max_torque_change_N_m: 0.02}  # > 0 each; any subset, the rest as shown
//     impact: {restitution: 0.5}       # optional, impact mode: e in [0, 1]
//     godobject:                       # optional, godobject mode (contact/god_object.h)
//       {stiffness_N_m: 1000, static_friction: 0, dynamic_friction: 0, shading: false,
//        texture_amplitude_m: 0, texture_wavelength_m: 0.001}   # k > 0; 0 ≤ μ_d ≤ μ_s; A ≥ 0;
//                                      # λ > 0; any subset, the rest as shown
//     material:                        # optional, material mode (contact/material_contact.h)
//       max_stiffness_N_m: 600         # > 0: the device's k_max
//       max_damping_N_s_m: 2           # ≥ 0: b_max
//       tool: {stiffness: 1, viscosity: 0, stickiness_N: 0, friction_N_m: 0}   # as objects'
//       body: {stiffness: 1, viscosity: 0, stickiness_N: 0, friction_N_m: 0}   # the body's
//     lcp_max_rows: 512                # ≥ 1, ≥ 3 with friction: rows the 1 kHz lcp solver
//                                      # holds (≈ 16 n² bytes, 24 with friction, four solvers:
//                                      # refused beyond this machine's memory); the frame sends
//                                      # at most this many (the far candidates last); steps with
//                                      # more active ones render the linear model (a warning)
//     lcp_friction_sweeps: 5           # ≥ 1, contact.law friction only: the lcp friction
//                                      # solve's sweeps per haptic step (its time bound;
//                                      # contact/haptic_friction_solver.h)
//     lcp_reach_m_s: 0.005             # ≥ 0: of the candidates the lcp model carries, the
//                                      # active ones and those an approach this much faster
//                                      # engages within a frame couple through the body; the
//                                      # others travel uncoupled (smaller models;
//                                      # docs/CONTACT.md). 0: all coupled
//     safety:                          # optional: the haptic process's limits
//     (device/haptic_safety.h)
//       {max_force_N: 10, max_torque_N_m: 0.5, max_force_rate_N_s: 5000,
//        max_torque_rate_N_m_s: 250, device_stale_s: 0.005, model_stale_s: 0.1,
//        blend_time_s: 0.01}           # > 0 each; any subset, the rest as shown
//   device:                            # required with a tool
//     trajectory:                      # scripted device motion (core/scripted_trajectory.h)
//       - {t_s: 0.0, position_m: [0, 0, 0.09], rotation_vector_rad: [0, 0, 0], button: false}
//                                      # ≥ 1 waypoint; t_s ≥ 0 and strictly increasing;
//                                      # rotation_vector_rad optional, default 0; button
//                                      # (true | false, default false) held until the next
//     hand: {mass_kg: 0.3, k_N_m: 300, b_N_s_m: 10}   # optional: the simulated hand of
//                                      # `hapsim haptic --device hand`; mass > 0, k, b ≥ 0
//   task:                              # optional (with a tool): the trainee's task (`hapsim
//                                      # train`): touch every target with the tissue force
//                                      # inside the band for hold_s in one go (with a grasper:
//                                      # bring the held tissue there, pulling inside the band;
//                                      # the points slipped from the jaws are scored too)
//     targets:                         # ≥ 1; names unique
//       - {name: left_lobe, position_m: [0.02, 0, 0.03], radius_m: 0.008}   # radius > 0
//     force_band_N: [0.5, 2.0]         # 0 ≤ min < max; default [0.5, 2.0]
//     hold_s: 0.5                      # > 0, default 0.5
//     force_limit_N: 4.0               # > band max, default 4: time above it is scored
//     time_limit_s: 60                 # > 0, default the scene's duration (time.num_steps·dt_s)

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "contact/contact_solver.h"
#include "contact/god_object.h"
#include "contact/visual_frame.h"
#include "core/mesh_transform.h"
#include "core/rigid_tool.h"
#include "core/scripted_trajectory.h"
#include "core/virtual_coupling.h"
#include "device/device_backend.h"
#include "device/geometric_haptic_contact.h"
#include "device/haptic_mode.h"
#include "device/haptic_safety.h"
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
  enum class Kind { kBox, kEllipsoid, kFile, kSurface };
  Kind kind = Kind::kBox;
  AxisAlignedBox box;                               // kBox
  Eigen::Vector3i cells = Eigen::Vector3i::Ones();  // kBox: lattice cells per axis
  // kBox: cells graded towards this point, `ratio` times larger at the farthest faces
  // (fem::MakeGradedAxis); ratio 1: uniform.
  Eigen::Vector3d grading_focus_m = Eigen::Vector3d::Zero();
  double grading_ratio = 1.0;
  double grading_circle_radius_m = 0.0;  // kBox: > 0, a ring of nodes on this circle (O-grid)
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();  // kEllipsoid
  Eigen::Vector3d radii_m = Eigen::Vector3d::Ones();   // kEllipsoid
  double cell_size_m = 0.0;  // kEllipsoid: lattice cell edge; kSurface: the tets' edge
  std::string file;          // kFile, kSurface: path resolved against the scene file's folder
  // kFile, kSurface: the file's units, rotation and placement (config/simulation_sections.h)
  MeshTransform transform;
  // kSurface: finer cells near a point (fem::SurfaceMeshOptions); refine_cell_size_m 0: none.
  Eigen::Vector3d refine_near_m = Eigen::Vector3d::Zero();
  double refine_cell_size_m = 0.0;
  double refine_radius_m = 0.0;
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

// A surface the body's tets carry (fem/surface_embedding.h): `collision` or `visual`.
struct EmbeddedSurfaceSource {
  std::string file;         // closed OBJ/STL, path resolved against the scene file's folder
  MeshTransform transform;  // its units, rotation and placement, as a mesh file's
  SourceLocation location;
};

struct BodyScene {
  MeshSource mesh;
  // `element: p2`: quadratic tets (fem/quadratic_tet.h), a node added on every edge of the mesh
  // (on a `surface:` mesh, the boundary's moved onto that surface: fem/curved_boundary.h);
  // `p1` (the default): linear tets. A mesh file of 10-node tets (Gmsh type 11) is quadratic
  // whatever this says.
  bool quadratic = false;
  std::optional<EmbeddedSurfaceSource> collision_surface;  // contacts found on it; else boundary
  std::optional<EmbeddedSurfaceSource> visual_surface;     // the viewer draws it; else boundary
  fem::Material material;
  fem::FemOptions options;
  std::optional<AxisAlignedBox> fixed;
  SourceLocation fixed_location;
  std::vector<NodalLoad> loads;
  std::vector<Probe> probes;
};

// A deformable object of `objects` after the first (Scene::more_bodies).
struct DeformableObjectScene {
  std::string name;
  BodyScene body;
  SourceLocation location;  // its `deformable` entry
};

// A rigid object of `objects`, resolved: a mesh file read.
struct RigidObjectScene {
  contact::RigidObject object;       // name, shape (in its own frame O), X_WO
  std::string mesh_file;             // ToolShape::Kind::kMesh: the file read (resolved path)
  SourceLocation location;           // the `objects[i]` entry
  SourceLocation friction_location;  // its friction_coefficient key, if given
  contact::Material material;        // the material mode's (haptic.mode material), paper 003
};

// The rigid tool, resolved: a mesh file read, mass properties computed.
struct ToolScene {
  ToolModel model;          // shape in T, mass, body inertia (MakeToolModel / …WithMass)
  ToolState initial_state;  // at rest at position_m, q_WT = exp(rotation_vector_rad)
  std::string mesh_file;    // ToolShape::Kind::kMesh: the file read (resolved path)
  SourceLocation location;  // the `tool` section
  bool point = false;       // shape `point`: a 3-DOF point (a sphere of its radius in the frame)
  std::optional<contact::GraspOptions> grasp;  // `grasp`: the tool is a grasper
};

// Tool–body contact law: contact::ContactLaw (equality, unilateral, friction).
using ContactLaw = contact::ContactLaw;

// Defaults are those of contact::ResponseOptions and contact::DetectionOptions.
struct ContactScene {
  ContactLaw law = ContactLaw::kUnilateral;
  double friction_coefficient = 0.0;  // μ, kFriction only
  double stabilization_beta = 0.2;    // in [0, 1]
  double restitution = 0.0;           // e in [0, 1]
  double margin_m = 1e-3;             // detection margin, m
  bool tool_features = true;          // tool features and edges against faces (detection)
  contact::ComplianceMethod compliance = contact::ComplianceMethod::kWarped;
  contact::ModelComplianceStep model_compliance_step = contact::ModelComplianceStep::kAuto;
};

// What the haptic side renders: see device/haptic_mode.h.
using HapticMode = device::HapticMode;

struct HapticScene {
  double rate_hz = 1000.0;
  HapticMode mode = device::kDefaultHapticMode;
  int lcp_max_rows = 512;
  int lcp_friction_sweeps = 5;   // contact.law friction: Gauss–Seidel sweeps per lcp step
  double lcp_reach_m_s = 0.005;  // lcp rows coupled: active and those this approach engages
  device::SafetyLimits safety;
  int steps_per_frame = 0;  // rate_hz · dt_s (an integer ≥ 1); set only when there is a tool
  // penalty, material, impact modes (the rigid objects' materials come from `objects`).
  device::GeometricContactParams geometric;
  // godobject mode (contact/god_object.h); the proxy radius is the point tool's radius.
  contact::GodObjectParams godobject;
};

// A palpation target of the task: a ball on or near the tissue's rest surface.
struct PalpationTarget {
  std::string name;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  // centre, world
  double radius_m = 0.0;
  SourceLocation location;
};

struct TaskScene {
  std::vector<PalpationTarget> targets;
  double force_band_min_N = 0.5;
  double force_band_max_N = 2.0;
  double hold_s = 0.5;
  double force_limit_N = 4.0;
  double time_limit_s = 0.0;  // the scene's duration when not given
};

// The value contact::ToString / device::ToString names `name`, or nullopt (command-line overrides).
std::optional<ContactLaw> ParseContactLaw(const std::string& name);
std::optional<HapticMode> ParseHapticMode(const std::string& name);
std::optional<contact::ComplianceMethod> ParseComplianceMethod(const std::string& name);

// Why `mode` cannot take contact.model_compliance_step `step`, or nullopt if it can: the
// haptic-step compliance is built (and paid for every frame) for the linear contact model, which
// only hybrid, linear, lcp and reference read. The scene's own mode is checked as it is read; a
// mode given on the command line by ResolveHapticMode.
std::optional<std::string> WhyModelComplianceStepRefused(contact::ModelComplianceStep step,
                                                         HapticMode mode);
// Why `mode` cannot render a grasper's bilateral rows, or nullopt if it can: the geometric and
// god-object modes search their own contacts at 1 kHz and would not feel the held tissue.
std::optional<std::string> WhyGraspRefused(HapticMode mode);

struct Scene {
  std::string file;  // the path it was loaded from
  std::string name;
  std::string description;
  Eigen::Vector3d gravity_m_s2{0.0, 0.0, -9.81};
  double dt_s = 0.0;
  int num_steps = 0;
  std::optional<BodyScene> body;   // the first deformable object: `body`, or the first entry of
  std::string body_name = "body";  // `objects` that is deformable
  // The other deformable objects, in order. config::MakeSceneBody builds them and the first as
  // one FEM body (fem::MergeModels), with the first object's FEM options and damping.
  std::vector<DeformableObjectScene> more_bodies;
  std::vector<RigidObjectScene> rigid_objects;  // the rigid entries of `objects`, in order
  // The simulation sections. All of them need a tool; with a tool, coupling and a device
  // trajectory are required and contact and haptic take their defaults when absent.
  std::optional<ToolScene> tool;
  CouplingParams coupling;
  ContactScene contact;
  HapticScene haptic;
  std::vector<Waypoint> trajectory;  // device.trajectory, times strictly increasing
  device::HandParams hand;           // device.hand: `hapsim haptic --device hand`
  std::optional<TaskScene> task;     // `hapsim train`
};

// Loads and validates a scene file. Throws hapsim::InputError naming file, line and key.
Scene LoadScene(const std::string& path);

// Same, from YAML text; `file_label` names it in errors and `base_dir` resolves mesh files.
Scene ParseScene(const std::string& yaml_text, const std::string& file_label,
                 const std::string& base_dir);

}  // namespace hapsim::config
