#pragma once
// Contact between the deformable body's separate objects (issue 28 item 2: organs that touch).
// Several deformable objects are one FEM system (fem::MergeModels), so their contact rows need no
// new machinery: a row's J_u reaches both objects' nodes and the frame's one compliance
// W = J_u A_u⁻¹ J_uᵀ holds both sides' (and their coupling through the tool's other rows).
//
// The objects are the models merged into the body, in the scene's order
// (fem::Model::object_first_nodes; a body of one object has no such contacts, whatever its mesh).
// Each object's free surface nodes are tested against the other objects' boundary triangles
// (all of them: a face of fixed nodes is still a surface to rest on): a node a near a triangle (b1,
// b2, b3) of another object, its closest point q = Σ w_k x_bk and the triangle's outward normal n,
// gives
//
//   gap = (x_a − q)·n,   nodes {a, b1, b2, b3}, weights {1, −w1, −w2, −w3}
//
// so that J_u's row is c = n·(u̇_a − Σ w_k u̇_bk), the gap's rate (the normal's own turn left out,
// as on the tool's faces). The "tool" side of the Contact is the triangle (p_tool = q, n out of
// it), the "body" side the node; on_tool false and no rigid object, like a body node on a tray,
// so every law, the compliance, the linear model and the 1 kHz rows take them as they take those.
// Both directions are tested (A's nodes on B's faces and B's on A's): the interface is held from
// both sides, and the unilateral solve shares the load of the near-redundant pairs.
//
// Candidates are found per pair of objects inside the overlap of the one's free surface nodes'
// box, grown by each node's reach, and the other's faces' box, then tested node against triangle:
// O(n_a n_t) in that overlap only, which is the contact interface, not the objects.
// Not handled (docs/CONTACT.md): an object against itself where it folds, embedded `collision:`
// surfaces (the objects meet at their tets' boundary) and quadratic faces' curvature (their four
// flat sub-triangles).

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "contact/contact.h"
#include "fem/model.h"

namespace hapsim::contact {

class BodyBodyContacts {
 public:
  // `body` must outlive this. margin_m: a node within this distance of another object's face
  // (plus the frame's sweep) is a candidate, as for the tool (DetectionOptions::margin_m).
  BodyBodyContacts(const fem::Model& body, double margin_m);

  int num_objects() const { return static_cast<int>(surface_nodes_.size()); }
  int object_of_node(int node) const { return object_of_node_[static_cast<size_t>(node)]; }

  // Appends the node–face contacts between different objects for a frame that moves the nodes
  // from x_start_m to x_end_m (3N each, world, m); the gaps are at the start.
  void AddContacts(const Eigen::VectorXd& x_start_m, const Eigen::VectorXd& x_end_m,
                   std::vector<Contact>* contacts) const;

  // The deepest node of one object inside another at positions x_m, if any is deeper than
  // tolerance_m: which objects, and how deep (m, > 0).
  struct Overlap {
    int node_object = -1, face_object = -1;  // different objects
    double depth_m = 0.0;
  };
  std::optional<Overlap> FindDeepestOverlap(const Eigen::VectorXd& x_m, double tolerance_m) const;

 private:
  // Calls visit(node, face, closest point q on it, the face's unit outward normal, the face's
  // object) for every free surface node within threshold(node) of a face of another object: the
  // nearest such face (of those as near, the one the node lies most in front of).
  template <typename Visit, typename Threshold>
  void ForEachCandidate(const Eigen::VectorXd& x_m, const Threshold& threshold,
                        const Visit& visit) const;

  const fem::Model& body_;
  double margin_m_;
  std::vector<int> object_of_node_;
  std::vector<std::vector<int>> surface_nodes_;  // per object: its free boundary nodes
  std::vector<std::vector<int>> triangles_;      // per object: columns of surface_triangles
};

}  // namespace hapsim::contact
