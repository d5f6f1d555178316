#pragma once
// God-object (constrained proxy) rendering of a point against triangle meshes, with friction,
// force shading and a bump texture (paper 004: C. Zilles, "Haptic Rendering with the Toolhandle
// Haptic Interface", MIT SM thesis 1995, ch. 3 and 4; Zilles & Salisbury, IROS 1995).
//
// Frames: W world; O the frame of one mesh (its vertices are given in O, placed at X_WO). The
// haptic interface point (HIP) is the device's position in W; the god-object is where the point
// would be if the surfaces were infinitely stiff. Force on the device (thesis eq. 3.1, 4.8):
//
//   F = k (p_proxy − p_hip),
//
// p_proxy the rendered proxy (the stiction point below; the god-object itself without friction).
//
// One step (thesis §3.2.2–3.2.3). Each triangle f is a one-sided constraint: its plane, moved out
// along its outward unit normal n_f by the proxy radius r, n_f·x = c_f = n_f·a_f + r. Its edges
// are widened in that plane by r tan(θ/2) where the neighbouring face makes a convex exterior
// dihedral angle θ (so the moved-out planes of the two faces meet; capped at θ ≈ 152°), by r at
// a boundary edge, by 0 at a flat or concave edge, plus ε everywhere so that a path through a
// shared edge hits one of its faces. (The moved-out surface thus has sharp edges where the exact
// Minkowski sum with a ball of radius r is rounded.)
//   goal ← p_hip; active ← {}
//   repeat: find the first widened, moved-out triangle that the segment (god-object of the last
//     step → goal) crosses from its front (n·x − c ≥ 0 at the start, < 0 at the end), among those
//     not active; none: stop. Add it; goal ← argmin |x − p_hip|² subject to n_i·x = c_i + ε for
//     the active planes (thesis eq. 3.4–3.7: with Lagrange multipliers l,
//         [ I   N ] [x]   [p_hip]
//         [ Nᵀ  0 ] [l] = [c + ε],   N = [n_1 … n_k] (3 x k), k ≤ 3,
//     solved as (NᵀN) l = Nᵀ p_hip − (c + ε), x = p_hip − N l; for k = 3, x = N⁻ᵀ (c + ε), the
//     corner). At most three active planes.
//   The god-object rests ε above its planes (thesis footnote 3), so every step re-finds them
//   while the HIP is behind, and a plane the HIP has left is not re-added. Planes whose normals
//   are (nearly) dependent on the active ones (parallel faces, a fourth plane through a concave
//   edge) replace an active one when that leaves the goal in front of the replaced plane (the
//   thesis' "hidden surface removal", §3.3.3); otherwise (and after six searches) the
//   god-object stops where the path met that plane, which is in front of every plane.
// Convex edge (thesis fig. 3-5): the god-object slides in the first face's plane past the edge
// (one step), and the next step's path from there crosses the second face. Concave corner: two
// planes hold it on their line of intersection, three at their common point.
//
// Deforming meshes (SetMeshVertices: the body's surface at each visual frame) carry a resting
// god-object and its stiction point on their first triangle, at the same (u, v, height). In a
// concave place that alone can leave the point behind a neighbouring face's moved-out plane (at
// the bottom of a dimple the valid rest is where the planes meet, higher up), from where the next
// path would miss that face and fall through. So the carried point is re-seated: it is
// approached from 2r + (the largest vertex move) + ε out along its face's normal, and stops at the
// first moved-out face met on the way.
//
// Moving meshes (thesis §3.3.2): each mesh keeps its pose of the last step; the path test for a
// mesh runs in its frame O from the last god-object, carried along with the mesh
// (X_WO_last⁻¹ p), to X_WO⁻¹ goal. A god-object resting on a moving mesh therefore moves with it,
// and a mesh moving into a free proxy pushes it. Its stiction point is carried by the mesh of the
// first active constraint.
//
// Friction (thesis §4.1, §4.1.1, "friction with slip", two coefficients). The god-object is
// placed as without friction; the stiction point s follows it. With g the god-object,
//   normal force  F_n = k |g − p_hip|,   tangential force F_t = k |s − g|;
//   stuck while |s − g| ≤ μ_s |g − p_hip|; otherwise s slips toward g onto the line (s, g) until
//   |s − g| = μ_d |g − p_hip| (a new stiction point; thesis eq. 4.6 without damping).
// On the step contact begins, s is where the path first met the surface. Out of contact s = g.
// With μ_d < μ_s a steady slide gives the thesis' sawtooth (fig. 4-4) between μ_s F_n and
// μ_d F_n. On a curved surface s moves on the chord to g (approximation).
//
// Force shading, variant chosen: Morgenbesser & Srinivasan 1996 ("force shading"), applied as a
// rotation. With exactly one active constraint, the interpolated unit normal at the god-object's
// contact point,
//   n_s = normalize(Σ w_i N_i), w the barycentric weights of the closest point of the triangle to
//   the god-object (clamped to the triangle), N_i the angle-weighted vertex normals
//   (Σ over the incident faces of (corner angle) n_f, normalised; Thürmer & Wüthrich 1998),
// replaces the face normal n_f: the whole force (normal part and friction) is turned by the
// smallest rotation taking n_f to n_s (so |F| and the friction ratio are kept). The god-object,
// the constraint search and friction are unchanged (not Ruspini et al.'s 1997 two-pass proxy:
// that moves the proxy off the polyhedron and needs a second search). Across an edge whose two
// vertices have the same normals on both sides, n_s is continuous in the contact point; at a
// convex edge the god-object still jumps when it drops onto the second face (thesis §4.2.1), so
// the direction changes by the interpolated turn over that jump. Two or three active planes: no
// shading (the force is the constrained solution's). Like all force shading, not passive.
//
// Bump texture, variant chosen: a height offset of the single active constraint plane,
//   h = A sin(2π (t_O·p_O)/λ),   p_O the rendered proxy in the contacted mesh's frame,
//   t_O a fixed unit tangent direction in O (texture moves with the mesh),
// applied to the output only: F += k h n_f, as if the plane were n·x = c + h (for one plane the
// constrained optimum moves by exactly h n). Not to the god-object's state, so the search stays
// on the polyhedron and a negative h cannot put the next step's start behind the surface. Chosen
// over a gradient-perturbed normal (thesis §4.3.2 eq. 4.11) because it is bounded (|ΔF| ≤ k A),
// needs no small-angle limit (the thesis reports instability beyond about 5° of normal tilt) and
// is the thesis' "magnitude increased or decreased by the bump map"; it gives no lateral force.
//
// Allocation: AddMesh and the constructor allocate; Step allocates nothing; SetMeshVertices
// allocates nothing (it refits the tree and recomputes normals and edge widths in place).
// Not implemented: damping (thesis eq. 3.2), per-object stiffness, decomposing the force among
// several touched objects.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <vector>

#include "core/eigen_types.h"
#include "core/tool_shape.h"

namespace hapsim::contact {

struct GodObjectParams {
  double stiffness_N_m = 1000.0;       // k > 0
  double proxy_radius_m = 0.0;         // r ≥ 0
  double surface_epsilon_m = 1e-9;     // ε > 0: how far above its planes the god-object rests
  double static_friction = 0.0;        // μ_s ≥ 0
  double dynamic_friction = 0.0;       // 0 ≤ μ_d ≤ μ_s
  bool shading = false;                // force shading (header comment)
  double texture_amplitude_m = 0.0;    // A ≥ 0; 0: no texture
  double texture_wavelength_m = 1e-3;  // λ > 0 (checked when A > 0)
  Eigen::Vector3d texture_direction_O = Eigen::Vector3d::UnitX();  // t_O, normalised on use
};

// Throws std::invalid_argument with a message naming the first bad parameter.
void ValidateGodObjectParams(const GodObjectParams& params);

class GodObject {
 public:
  // One active constraint: triangle `triangle` of mesh `mesh`.
  struct Constraint {
    int mesh = -1;
    int triangle = -1;
    Eigen::Vector3d normal_W = Eigen::Vector3d::UnitZ();  // n, unit, outward, W
    double offset_m = 0.0;  // c: the plane n·x = c moved out by r (the god-object is at c + ε)
  };
  // The first crossing of a segment p0 + t (p1 − p0), t ∈ [0, 1], in a mesh's frame O.
  struct Crossing {
    int triangle = -1;  // −1: none
    double t = 1.0;
  };

  // Throws std::invalid_argument for bad parameters (ValidateGodObjectParams).
  explicit GodObject(const GodObjectParams& params);

  // Adds a mesh (vertices in O, triangles counter-clockwise seen from outside; need not be
  // closed) at pose X_WO; returns its id (0, 1, …). Degenerate (zero-area) triangles are kept
  // but never touched. Throws std::invalid_argument for an empty mesh or an index out of range.
  int AddMesh(const TriangleMesh& mesh_O, const Eigen::Isometry3d& X_WO);
  // Where mesh `id` is now; the next Step carries a god-object resting on it along.
  // Throws std::invalid_argument for a bad id.
  void SetMeshPose(int id, const Eigen::Isometry3d& X_WO);
  // New vertex positions of mesh `id`, in O (3 x V, same V and topology as added): the
  // deformable body's surface of the last visual frame. Refits the tree, recomputes face and
  // vertex normals and edge widths; allocates nothing. A god-object (and stiction point) resting
  // on the mesh keeps its coordinates on its first active triangle, (u, v, h) with
  // p = a + u (b − a) + v (c − a) + h n, so the surface carries it; a free proxy that the moving
  // surface passes over is not detected (unlike SetMeshPose's rigid motion). The tree keeps its
  // split (refit only), so it loosens under large deformations. Throws std::invalid_argument
  // for a bad id or a size mismatch.
  void SetMeshVertices(int id, const Matrix3Xd& vertices_O_m);

  // Places the god-object and the proxy at p_W_m, out of contact (no constraint).
  void Reset(const Eigen::Vector3d& p_W_m);

  // One haptic step for the HIP at hip_W_m (header comment). The first step after construction
  // (without Reset) starts the god-object at the HIP. Allocates nothing.
  void Step(const Eigen::Vector3d& hip_W_m);

  // Results of the last step.
  const Eigen::Vector3d& proxy_W_m() const { return proxy_W_m_; }  // rendered (stiction) point
  const Eigen::Vector3d& god_object_W_m() const { return god_object_W_m_; }  // frictionless
  const Eigen::Vector3d& force_W_N() const { return force_W_N_; }            // on the device, W, N
  double normal_force_N() const { return normal_force_N_; }  // k |g − p_hip| (+ k h), N
  int num_active_constraints() const { return num_active_; }
  const Constraint& active_constraint(int i) const { return active_[i]; }  // 0 ≤ i < num
  bool in_contact() const { return num_active_ > 0; }
  bool stuck() const { return stuck_; }  // friction holds the proxy at its stiction point

  int num_meshes() const { return static_cast<int>(meshes_.size()); }
  const Eigen::Isometry3d& mesh_pose(int id) const { return meshes_.at(id).X_WO; }
  // (3 x V) unit angle-weighted vertex normals of mesh `id`, O.
  const Matrix3Xd& vertex_normals_O(int id) const { return meshes_.at(id).vertex_normals_O; }
  const GodObjectParams& params() const { return params_; }

  // The first front crossing of p0_O → p1_O with mesh `id`'s widened, moved-out triangles
  // (header comment), skipping the triangles in `exclude` (−1 entries: none; the active
  // constraints' triangles), through the AABB tree; and the same by testing every triangle (a
  // second method, for tests).
  using Exclusions = std::array<int, 3>;
  Crossing CalcFirstCrossing(int id, const Eigen::Vector3d& p0_O_m, const Eigen::Vector3d& p1_O_m,
                             const Exclusions& exclude = {-1, -1, -1}) const;
  Crossing CalcFirstCrossingBruteForce(int id, const Eigen::Vector3d& p0_O_m,
                                       const Eigen::Vector3d& p1_O_m,
                                       const Exclusions& exclude = {-1, -1, -1}) const;

 private:
  struct Node {               // AABB tree node, pre-order: the left child follows its parent
    Eigen::AlignedBox3d box;  // of the widened, moved-out triangles below, O, m
    int first = 0;            // leaf: its triangles are order[first, first + count)
    int count = 0;            // > 0: leaf
    int right = -1;           // internal: index of the right child
  };
  struct Mesh {
    Matrix3Xd vertices_O_m;      // (3 x V)
    Matrix3Xi triangles;         // (3 x F)
    Matrix3Xi neighbours;        // (3 x F) triangle across edge k = (k, k+1), −1: none
    Matrix3Xd face_normals_O;    // (3 x F) unit outward (zero for a degenerate triangle)
    Eigen::VectorXd offsets_m;   // (F) c_f = n_f·a_f + r
    Matrix3Xd edge_widths_m;     // (3 x F) in-plane widening of edge k (header comment)
    Matrix3Xd vertex_normals_O;  // (3 x V) unit, angle-weighted
    std::vector<Node> nodes;
    std::vector<int> order;  // triangle indices, grouped by leaf
    Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
    Eigen::Isometry3d X_WO_last = Eigen::Isometry3d::Identity();  // at the last step
  };

  // Face normals, offsets, edge widths and vertex normals from the vertices.
  void CalcGeometry(Mesh* mesh) const;
  // A point carried on face f of mesh `id` after SetMeshVertices, moved to where it is in front
  // of every moved-out face: the first front crossing met coming down to it from lift_m out
  // along the face's normal (ε in front of it), or the point itself if none is met.
  Eigen::Vector3d Reseat(int id, int f, const Eigen::Vector3d& p_W_m, double lift_m) const;
  // Recomputes the node boxes bottom-up.
  void RefitTree(Mesh* mesh) const;
  int BuildNode(Mesh* mesh, int first, int count, std::vector<Eigen::AlignedBox3d>* boxes,
                std::vector<Eigen::Vector3d>* centres);
  Eigen::AlignedBox3d CalcTriangleBox(const Mesh& mesh, int f) const;
  // Parameter t of the front crossing of triangle f, or a value > 1 if none.
  double CalcTriangleCrossing(const Mesh& mesh, int f, const Eigen::Vector3d& p0_O,
                              const Eigen::Vector3d& p1_O) const;
  // The first front crossing over all meshes of the path from the last god-object to goal_W,
  // skipping active constraints (mesh −1 if none): its plane, the crossing point moved ε out
  // (W) and its path parameter.
  Constraint FindFirstCrossing(const Eigen::Vector3d& goal_W, Eigen::Vector3d* point_W,
                               double* t) const;
  // The force shading normal at the god-object for constraint c, W.
  Eigen::Vector3d CalcShadingNormal(const Constraint& c) const;
  // The three parts of Step (god_object.cc).
  Eigen::Vector3d PlaceGodObject(const Eigen::Vector3d& hip_W_m);
  void ApplyFriction(const Eigen::Vector3d& hip_W_m, bool was_in_contact,
                     const Eigen::Vector3d& first_point_W);
  void ApplyTextureAndShading();

  GodObjectParams params_;
  std::vector<Mesh> meshes_;

  // State (written by Step).
  bool initialised_ = false;
  Eigen::Vector3d god_object_W_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d proxy_W_m_ = Eigen::Vector3d::Zero();  // stiction point
  Eigen::Vector3d force_W_N_ = Eigen::Vector3d::Zero();
  double normal_force_N_ = 0.0;
  std::array<Constraint, 3> active_;
  int num_active_ = 0;
  bool stuck_ = false;
};

}  // namespace hapsim::contact
