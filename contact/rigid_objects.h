#pragma once
// The fixed rigid objects of a scene (DESIGN.md §9: a tray under an organ, a cavity wall, a peg
// board) and their contacts, for stage 4 of the visual frame.
//
// A rigid object is one of the tool's shapes (core/tool_shape.h: sphere, capsule, cylinder, box,
// closed mesh) placed at a fixed pose X_WO. It has no degrees of freedom, so its contact rows
// carry no compliance of its own: a tool contact has the tool's J_v, J_ω and no J_u; a body
// contact has the body's J_u and no tool terms. Both kinds enter the one response with the
// tool–body contacts (unilateral, friction or equality, as the scene's law), so a tissue resting
// on a tray stiffens the tissue under the tool in the linear contact model.
//
// Contacts, each measured at the start of the frame with the exact signed distance d of the
// object (contact/tool_distance.h), and reported when d ≤ τ = margin + sweep bound:
//   tool feature point v (box corner, rim point, mesh vertex) against the object:
//       n = −m (m the object's outward normal at its closest point q), p_tool = v, p_body = q;
//   smooth tool core c of radius r (a sphere's centre; points along a capsule's segment, spaced
//   no more than half its radius; the rim points of a rounded cylinder's inner sharp cylinder,
//   r its edge radius) against the object: gap d − r, p_tool = c − r m, p_body = q;
//   object feature point (its corners, rim or vertices) against the tool: gap = the tool's signed
//   distance there, n = the tool's outward normal, p_tool = the tool's closest point;
//   deformable body surface node x against the object: n = m (out of the object, towards the
//   node), p_tool = q (the object's point; the field's name keeps the Contact layout), p_body = x.
// With n so oriented, gap = (p_body − p_tool)·n in every case, as in contact/contact.h.
// The sweep bound of the tool is |Δx| + θ R_tool; of a node, its own displacement in the frame.
// What is left approximate: a cylinder tool's side and a box tool's faces against a convex
// object edge or corner (only the object's own feature points and the tool's feature points are
// tested, no edge-versus-edge); a capsule's segment is sampled, so against a sharp object edge
// it may sink by up to the sagitta between samples (r (1 − √(1 − 1/16)) ≈ 3% of r: an edge lies
// at most r/4 from the nearest sample).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "contact/contact.h"
#include "contact/tool_distance.h"
#include "core/tool_shape.h"

namespace hapsim::contact {

// A rigid object of the scene: fixed in the world.
struct RigidObject {
  std::string name;
  ToolShape shape;  // in the object frame O (origin at the shape's centre, as for the tool)
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
};

// The object's bounding box in the world frame.
Eigen::AlignedBox3d CalcWorldBox(const RigidObject& object);

class RigidObjectContacts {
 public:
  // Builds each object's distance field and feature points once. Throws std::invalid_argument
  // for a bad shape (as ToolDistanceField does) or a negative margin.
  RigidObjectContacts(std::vector<RigidObject> objects, const ToolShape& tool, double margin_m);

  // Tool against every object: appends contacts with on_tool = true and no body nodes.
  void AddToolContacts(const Eigen::Isometry3d& X_WT_start, const Eigen::Isometry3d& X_WT_end,
                       std::vector<Contact>* contacts) const;

  // The nodes `surface_nodes` of a deformable body against every object: appends contacts with
  // on_tool = false, one node of weight 1. x_start_m, x_end_m: (3N) node positions, world, m.
  void AddBodyContacts(const std::vector<int>& surface_nodes, const Eigen::VectorXd& x_start_m,
                       const Eigen::VectorXd& x_end_m, std::vector<Contact>* contacts) const;

  // The deepest object containing p_W_m: its signed distance (< 0 inside; the smallest over the
  // objects, +inf without objects), closest surface point and outward normal, world.
  struct Penetration {
    double distance_m = 0.0;
    Eigen::Vector3d closest_W_m = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal_W = Eigen::Vector3d::UnitZ();
  };
  Penetration CalcDeepest(const Eigen::Vector3d& p_W_m) const;

  int num_objects() const { return static_cast<int>(objects_.size()); }
  const RigidObject& object(int i) const { return objects_[i].object; }

 private:
  struct Placed {
    RigidObject object;
    ToolDistanceField field;
    Matrix3Xd points_O_m;         // (3 x K) the object's sample points (see the .cc), O
    double point_radius_m = 0.0;  // radius of the ball around each sample point
    Eigen::AlignedBox3d box_W_m;  // world bounding box of the object
  };
  // Appends the contact of tool point p_W (on the tool if radius 0, else the centre of a ball
  // of that radius) against object i when its gap is ≤ threshold_m.
  void AddPointContact(int i, const Eigen::Vector3d& p_W_m, double radius_m, double threshold_m,
                       std::vector<Contact>* contacts) const;

  std::vector<Placed> objects_;
  ToolDistanceField tool_field_;
  Matrix3Xd tool_points_T_m_;  // (3 x K) the tool's sample points, T
  double tool_point_radius_m_ = 0.0;
  double margin_m_ = 0.0;
};

}  // namespace hapsim::contact
