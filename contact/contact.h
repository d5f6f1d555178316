#pragma once
// One contact between the rigid tool and the deformable body (DESIGN.md §4), the tool and a fixed
// rigid object, or the body and a rigid object (§9; contact/rigid_objects.h), as collision
// detection produces it and the constraint solver consumes it.
//
// Sign conventions: n_W points out of the tool, towards the body. The gap is measured along n_W
// from the tool surface to the body point, gap = (p_body − p_tool)·n, negative when they
// interpenetrate. The body point is a combination of up to three nodes with barycentric weights
// (one node with weight 1 for a node-versus-tool contact; a face's three nodes for a tool feature
// point against a face; a body edge's two nodes for a tool edge against a body edge). On a
// collision surface embedded in the tets (fem/surface_embedding.h) the same one, two or three
// surface points are each carried by their tet's four nodes (ten in quadratic tets): up to thirty
// nodes, with the products of the two weights (`embedded`).
// A contact that touches no tool (a body node on a rigid object) has on_tool = false: its rows
// have no tool terms, and "tool" below then means the rigid object (p_tool_W_m is the object's
// point, n_W points out of the object). A contact with a rigid object has no body nodes on that
// side: the object has no degrees of freedom. An object the tool holds (grabbed) is part of the
// tool: its contacts have on_tool = true, rigid_object its index, and body nodes if they are
// with the body.
// A contact between two of the body's objects (contact/body_body_contacts.h) has on_tool false
// and no rigid object: its "tool" side is a face of one object (p_tool_W_m on it, n_W out of it),
// its body side a node of the other, and its weights are 1 for the node and −w_k for the face's
// nodes, so that the row measures the gap's rate between them.
// A contact between two rigid objects, one of them dynamic (contact/object_dynamics.h), has
// on_tool false and no body nodes: rigid_object is the object on its "tool" side (p_tool_W_m on
// it, n_W out of it) and other_object the one on its body side (p_body_W_m on it).
// A grasp row (contact/tissue_grasp.h) is a contact too: a body point held by the tool's jaws,
// its normal one of the tool frame's axes and its gap the point's offset from where the jaws
// took it along that axis. It is bilateral: held at c = b with λ of either sign (the tissue
// pulls), never dropped by the unilateral law.

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <initializer_list>

namespace hapsim::contact {

// The most nodes a body point combines: a face's three points, each on its tet's ten nodes (a
// quadratic tet's; a linear one's four make at most twelve).
inline constexpr int kMaxContactNodes = 30;

// kMaxContactNodes slots, none used.
constexpr std::array<int, kMaxContactNodes> NoContactNodes() {
  std::array<int, kMaxContactNodes> nodes{};
  for (int& node : nodes) node = -1;
  return nodes;
}

struct Contact {
  Eigen::Vector3d p_tool_W_m = Eigen::Vector3d::Zero();  // point on the tool surface, world, m
  Eigen::Vector3d p_body_W_m = Eigen::Vector3d::Zero();  // point on the body, world, m
  Eigen::Vector3d n_W = Eigen::Vector3d::UnitZ();        // unit normal out of the tool
  double gap_m = 0.0;                                    // signed gap along n_W, m
  // Body nodes and their weights (sum 1), in slots [0, k); the slots after are −1 and 0. Set
  // them with SetBodyNodes, which clears the rest: a brace list assigned to the array would fill
  // the slots it does not name with node 0.
  std::array<int, kMaxContactNodes> nodes = NoContactNodes();
  std::array<double, kMaxContactNodes> weights = {};
  bool embedded = false;  // the body point lies on an embedded collision surface
  // The one to three points of the surface the contact was found on (boundary nodes, or points of
  // an embedded surface before their tets' nodes replaced them), −1 unused: what names the
  // contact from frame to frame (ImpulseWarmStart).
  std::array<int, 3> surface_points = {-1, -1, -1};
  bool on_tool = true;    // false: a body node against a rigid object or another object's face
  int rigid_object = -1;  // the rigid object touched (index in the scene's list), −1: none
  int other_object = -1;  // two rigid objects touching: the one on the body side, −1: none
  bool bilateral = false;  // a grasp row: an equality whatever the law, λ of either sign

  void SetBodyNodes(std::initializer_list<int> body_nodes,
                    std::initializer_list<double> body_weights) {
    nodes.fill(-1);
    weights.fill(0.0);
    std::copy(body_nodes.begin(), body_nodes.end(), nodes.begin());
    std::copy(body_weights.begin(), body_weights.end(), weights.begin());
    std::copy(nodes.begin(), nodes.begin() + 3, surface_points.begin());
  }
};

// What a contact touches (sim_frame_t.contact_kind).
enum class ContactKind : std::int8_t {
  kToolBody = 0,        // the tool and the deformable body
  kToolObject = 1,      // the tool, or the object it holds, and a rigid object
  kBodyObject = 2,      // a body node and a rigid object
  kHeldObjectBody = 3,  // a body node and the object the tool holds
  kGrasp = 4,           // a body point held by the tool's jaws (one row per tool axis)
  kBodyBody = 5,        // a node of one deformable object and a face of another
  kObjectObject = 6,    // two rigid objects, one of them dynamic (falling, pushed)
};

inline ContactKind KindOf(const Contact& contact) {
  if (contact.bilateral) return ContactKind::kGrasp;
  if (!contact.on_tool) {
    if (contact.other_object >= 0) return ContactKind::kObjectObject;
    return contact.rigid_object >= 0 ? ContactKind::kBodyObject : ContactKind::kBodyBody;
  }
  if (contact.rigid_object < 0) return ContactKind::kToolBody;
  return contact.nodes[0] >= 0 ? ContactKind::kHeldObjectBody : ContactKind::kToolObject;
}

}  // namespace hapsim::contact
