#pragma once
// Collision detection between the rigid tool and the deformable body's surface (DESIGN.md §4,
// stage 4 of the visual frame): node-versus-tool, tool-feature-versus-face and
// tool-edge-versus-body-edge contacts, with a swept (speculative) search region so that a fast
// tool does not tunnel through a thin body.
//
// Pipeline of Detect():
//   1. refit the surface BVH at the start positions;
//   2. broad phase: FCL collide of the BVH against the tool primitive inflated by the threshold
//      τ = margin + sweep bound (a mesh tool: its bounding box inflated by τ) → candidate faces;
//   3. narrow phase (a) node versus tool: every node of a candidate face, once, with the exact
//      signed distance to the tool at the start pose; a contact when φ ≤ τ;
//   4. narrow phase (b) tool feature versus face: every tool feature point v (box corner,
//      cylinder rim point, mesh vertex) against the candidate faces that face it (outward normal
//      m opposite to the point's normal-cone axis): the nearest such face whose closest point q
//      has v − q within 45° of ±m gives φ = (v − q)·m (negative behind the face) and a contact
//      when φ ≤ τ, distributed to the face's nodes with the barycentric weights of q;
//      a sphere tool's centre c against every candidate face it is in front of, whose closest
//      point q lies inside the face or on an edge (a vertex is a node: stage 3): n from q to c,
//      φ = |c − q| − r, p_tool = c − r n, on the face's nodes with the weights of q (without it
//      a sphere smaller than a face sinks between the face's nodes by the sagitta, which is
//      all the way through once r is below the face's circumradius);
//   5. narrow phase (c) tool edge versus body edge (edge_contacts.cc): every edge of the
//      candidate faces, once, against every sharp tool edge (box edge, rim segment, convex mesh
//      edge between non-coplanar faces). The closest points of the two segments (Ericson §5.1.9)
//      must lie strictly inside both (end points are nodes or feature points: stages 3 and 4);
//      n = ±(d_tool × d_body)/|d_tool × d_body| out of the tool must lie in the tool edge's
//      normal cone (the wedge between its two faces' normals) and have n·m < 0 for one of the
//      body edge's two faces. Then φ = (p_body − p_tool)·n, a contact when −max_feature_penetration
//      ≤ φ ≤ τ, on the body edge's two nodes with weights (1 − t, t); except that a body edge
//      lying flat (within 1 mrad) against one of the tool edge's faces, with a node contact at
//      its node on that face's side, is already held by that contact;
//   6. merge: a feature or edge contact whose body point lies within feature_merge_distance of
//      another contact's body point with normals within 10° is a duplicate: only the deeper one
//      stays.
// What is left approximate: on a flat or nearly flat stretch of the body, an edge contact's
// normal is the common normal of the two segments, which tilts from the face normal by as much
// as the tool edge tilts from the face (a valid separating direction for the two segments, not
// the face's); a cylinder's rim, sharp or rounded, is the polygon through stage 4's rim points;
// a flat-lying body edge left to a node contact may sink by up to its length × 1e-3; edges
// within 1e-6 rad of parallel make no edge contact (the end point contacts of stages 3 and 4
// hold them); a capsule between nodes still sinks by up to the sagitta over one face.
//
// Embedded collision surface: when the body has one (fem::Model::collision_surface), the pipeline
// runs on its points (x_S = B x, fem/surface_embedding.h) in place of the boundary's nodes, and
// each contact's one to three surface points are then replaced by their tets' nodes, weights
// multiplied (≤ 12 nodes, Contact::embedded): the Jacobian row is H = B N, so everything that
// consumes contacts works unchanged. "Node" below then reads "surface point".
//
// Speculative contacts: with `continuous`, the sweep bound is |Δx_tool| + θ·R_tool + max|Δx_node|
// (θ the rotation angle between the two poses, R_tool the tool's bounding radius), an upper
// bound on how far any tool or surface point can move within the frame. Contacts are reported
// up to that distance; their gap is measured at the start, and the solver allows closing at
// most the gap within the frame (c ≥ −φ/Δt), so nothing crosses even when the free update would.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "contact/contact.h"
#include "contact/quadratic_surface.h"
#include "contact/surface_bvh.h"
#include "contact/tool_distance.h"
#include "core/tool_shape.h"
#include "fem/model.h"

namespace hapsim::contact {

struct DetectionOptions {
  double margin_m = 1e-3;                  // contacts are reported up to this gap (≥ 0), m
  bool continuous = true;                  // widen the search to the sweep start → end
  double feature_merge_distance_m = 1e-4;  // duplicate detection radius (≥ 0), m
  // A tool feature point lying behind a body face deeper than this is not touching that face:
  // behind-the-plane alone does not mean inside the body (a corner above a thin slab is behind
  // its bottom face). Penetrations are corrected every frame, so real ones stay shallow. m.
  double max_feature_penetration_m = 5e-3;
  bool edge_contacts = true;  // tool-edge-versus-body-edge contacts (pipeline step 5)
  // Tool-feature-versus-face contacts (pipeline step 4, its feature points: box corners, rim
  // points, mesh vertices); the sphere's centre against faces is step 4 too and always runs.
  bool feature_contacts = true;
};

// What the last Detect() call did.
struct DetectionStatistics {
  int num_candidate_triangles = 0;    // faces returned by the broad phase
  int num_node_contacts = 0;          // node-versus-tool contacts, before merging
  int num_feature_contacts = 0;       // tool-feature- and sphere-centre-versus-face contacts,
                                      // before merging
  int num_edge_contacts = 0;          // tool-edge-versus-body-edge contacts, before merging
  int num_contacts_before_merge = 0;  // node + feature + edge contacts
  int num_contacts_after_merge = 0;   // contacts returned
  double sweep_bound_m = 0.0;         // 0 without `continuous`
  double threshold_m = 0.0;           // margin + sweep bound
};

class CollisionDetector {
 public:
  // Keeps its own copies (the body's surface, the tool shape); `body` need not outlive it.
  // Throws std::invalid_argument for a negative margin or merge distance, a bad tool shape, or a
  // body without surface triangles.
  CollisionDetector(const fem::Model& body, const ToolShape& tool, const DetectionOptions& options,
                    SurfaceBvhKind bvh_kind = SurfaceBvhKind::kAabb);

  // Contacts of the tool against the body surface for one visual frame. Gaps and normals are
  // measured at the START configuration (x_start_m, X_WT_start); with `continuous` the search
  // region covers the sweep to the END configuration (x_end_m, X_WT_end: the free,
  // collision-free update). A contact is reported when φ ≤ margin + sweep bound. Without
  // `continuous`, the end configuration is ignored (φ ≤ margin). Clears and fills *contacts;
  // allocates only while its scratch buffers grow.
  // x_start_m, x_end_m: (3N) stacked node positions, world, m. Throws std::invalid_argument on a
  // size mismatch.
  // refit_tree = false skips step 1: the tree was refitted to x_start_m already (by an earlier
  // Detect or by Refit), as when the same body positions are searched at 1 kHz between frames;
  // on an embedded surface the points computed then are used, and x_start_m only until they are.
  void Detect(const Eigen::VectorXd& x_start_m, const Eigen::Isometry3d& X_WT_start,
              const Eigen::VectorXd& x_end_m, const Eigen::Isometry3d& X_WT_end,
              std::vector<Contact>* contacts, bool refit_tree = true);
  // Refits the surface tree to x_m (3N), for Detect with refit_tree = false.
  void Refit(const Eigen::VectorXd& x_m);
  // The gap up to which contacts are reported from now on (≥ 0, else std::invalid_argument): a
  // 1 kHz search whose margin changes every step (penalty's ε = v Δt).
  void SetMargin(double margin_m);

  const DetectionStatistics& statistics() const { return statistics_; }
  const DetectionOptions& options() const { return options_; }
  const ToolDistanceField& tool_distance() const { return tool_distance_; }
  const ToolFeatures& tool_features() const { return tool_features_; }

 private:
  // The positions the pipeline runs on: x_m itself, or the embedded surface's points (*scratch).
  const Eigen::VectorXd& SurfacePositions(const Eigen::VectorXd& x_m,
                                          Eigen::VectorXd* scratch) const;
  // Embedded surface: each contact's surface points replaced by their tets' nodes.
  void ExpandEmbeddedContacts(std::vector<Contact>* contacts) const;
  double CalcSweepBound(const Eigen::VectorXd& x_start_m, const Eigen::Isometry3d& X_WT_start,
                        const Eigen::VectorXd& x_end_m, const Eigen::Isometry3d& X_WT_end) const;
  void FindCandidateTriangles(const Eigen::Isometry3d& X_WT, double inflation_m);
  void AddNodeContacts(const Eigen::VectorXd& x_m, const Eigen::Isometry3d& X_WT,
                       std::vector<Contact>* contacts);
  // Spheres around runs of kToolRun consecutive spheres (centres in T, radii; 0 for points): each
  // run's centred at its members' mean centre and reaching a nanometre past the farthest member, so
  // that round-off never lets it reject what one of its members would keep. The feature points'
  // runs and the sharp edges' (each edge in the sphere about its midpoint) come from it.
  static void MakeRunSpheres(const Matrix3Xd& centers_T_m, const Eigen::VectorXd& radii_m,
                             Matrix3Xd* run_centers_T_m, Eigen::VectorXd* run_radii_m);
  void AddFeatureContacts(const Eigen::VectorXd& x_m, const Eigen::Isometry3d& X_WT,
                          std::vector<Contact>* contacts);
  // A sphere tool's centre against the candidate faces (pipeline step 4, sphere).
  void AddSphereFaceContacts(const Eigen::VectorXd& x_m, const Eigen::Isometry3d& X_WT,
                             std::vector<Contact>* contacts);
  void MergeDuplicates(int first_feature_contact, std::vector<Contact>* contacts);
  void AdvanceFrameStamp();
  // Edge stage (edge_contacts.cc): the body's surface edges and the tool's sharp edges, built
  // once by the constructor; the contacts, per frame.
  void MakeEdgeTopology();
  void AddEdgeContacts(const Eigen::VectorXd& x_m, const Eigen::Isometry3d& X_WT,
                       std::vector<Contact>* contacts);

  DetectionOptions options_;
  int num_body_nodes_ = 0;
  fem::EmbeddedSurface embedded_;  // the body's collision surface; empty: its boundary
  // Quadratic tets' boundary (no embedded surface): contacts re-weighted by the faces' quadratic
  // shape functions (contact/quadratic_surface.h); null otherwise.
  std::unique_ptr<QuadraticSurface> quadratic_;
  Matrix3Xi surface_triangles_;    // the boundary's faces (node indices) or the embedded surface's
  Eigen::VectorXd points_start_m_, points_end_m_;  // embedded: the points, (3P) world, m
  ToolDistanceField tool_distance_;
  ToolFeatures tool_features_;
  Eigen::AlignedBox3d mesh_box_T_m_;  // kMesh: bounding box of the tool mesh in T
  SurfaceBvh bvh_;
  DetectionStatistics statistics_;
  // Scratch, reused between calls.
  std::vector<int> candidate_triangles_;
  // Per candidate face, for AddFeatureContacts: its centroid and (circumradius + reach)², beyond
  // which no feature point can make a contact with it.
  struct FaceSphere {
    Eigen::Vector3d centre_W_m;
    double reach_m = 0.0;  // circumradius + reach
    double reach_sq_m2 = 0.0;
  };
  std::vector<FaceSphere> candidate_spheres_;
  // The tool's feature points in runs of kToolRun consecutive ones, each run in a sphere
  // (MakeRunSpheres); the candidate faces within reach of the run's sphere (scratch, its capacity
  // the surface's faces, as candidate_spheres_': AddFeatureContacts allocates nothing).
  static constexpr int kToolRun = 8;
  Matrix3Xd feature_run_centers_T_m_;
  Eigen::VectorXd feature_run_radii_m_;
  std::vector<int> faces_near_run_;
  std::vector<int> node_visited_;     // frame stamp per body node
  std::vector<int> node_in_contact_;  // frame stamp per body node that made a node contact
  std::vector<char> merged_away_;     // per contact of the current call
  int frame_stamp_ = 0;
  // Body surface edges: end nodes and the (up to two; −1 = none) surface triangles holding each.
  Eigen::Matrix<int, 2, Eigen::Dynamic> body_edge_nodes_;      // (2 x E_body)
  Eigen::Matrix<int, 2, Eigen::Dynamic> body_edge_triangles_;  // (2 x E_body)
  Matrix3Xi triangle_edges_;       // (3 x F) body edge of side k = (k, k+1 mod 3) of each triangle
  std::vector<int> edge_visited_;  // frame stamp per body edge
  // Sharp tool edges, in T: end points (indices into tool_features_.vertices_T_m); per edge
  // three unit columns: the bisector of its two faces' outward normals, then those normals; and
  // the cosine of the half-angle of the wedge they span (the edge's normal cone).
  Eigen::Matrix<int, 2, Eigen::Dynamic> tool_edges_;  // (2 x E_tool)
  Matrix3Xd tool_edge_normals_T_;                     // (3 x 3 E_tool)
  Eigen::VectorXd tool_edge_cone_cosines_;            // (E_tool)
  Matrix3Xd tool_edge_normals_W_;                     // scratch (3 x 3 E_tool), world
  Matrix3Xd tool_vertices_W_m_;                       // scratch (3 x V_tool), world, m
  Matrix3Xd tool_edge_midpoints_W_m_;                 // scratch (3 x E_tool), world, m
  Eigen::VectorXd tool_edge_half_lengths_m_;          // (E_tool): its bounding sphere's radius
  // Runs of kToolRun consecutive tool edges, each run in a sphere that holds its edges' spheres
  // (MakeRunSpheres): centre in T and radius (G = E_tool / kToolRun rounded up).
  Matrix3Xd tool_edge_run_centers_T_m_;    // (3 x G)
  Eigen::VectorXd tool_edge_run_radii_m_;  // (G)
  Matrix3Xd tool_edge_run_centers_W_m_;    // scratch (3 x G), world, m
};

}  // namespace hapsim::contact
