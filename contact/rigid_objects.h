#pragma once
// The rigid objects of a scene (DESIGN.md §9: a tray under an organ, a cavity wall, a peg board)
// and their contacts, for stage 4 of the visual frame.
//
// A rigid object is one of the tool's shapes (core/tool_shape.h: sphere, capsule, cylinder, box,
// closed mesh) placed at a pose X_WO: fixed, moved by a script (its pose a function of time),
// grabbed by the tool, or dynamic (it falls and is pushed: contact/object_dynamics.h). Only a
// dynamic one has degrees of freedom of its own; the others' contact rows carry no compliance of
// their own: a tool contact has the tool's J_v, J_ω and no J_u; a body contact has the body's J_u
// and no tool terms. A dynamic object's rows get its velocity and its compliance from the
// visual frame (contact/object_dynamics.h), and it also touches the other objects.
//
// Grabbing (paper 003, selection and grabbing modes): while grabbed, an object is attached to the
// tool at the relative pose X_TO it had when grabbed, so it is part of the tool. Its contacts
// with the body and with the other objects are tool contacts (on_tool = true, with the tool's
// J_v and J_ω about the tool's centre of mass), so the trainee feels what the grabbed object
// touches, through the tool's virtual coupling to the device; the tool makes no contacts with it.
// Both kinds enter the one response with the tool–body contacts (unilateral, friction or equality,
// as the scene's law), so a tissue resting on a tray stiffens the tissue under the tool in the
// linear contact model.
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
#include <optional>
#include <string>
#include <vector>

#include "contact/contact.h"
#include "contact/tool_distance.h"
#include "core/scripted_trajectory.h"
#include "core/tool_shape.h"

namespace hapsim::contact {

// A rigid object of the scene (model data: how it moves, not where it is now).
struct RigidObject {
  std::string name;
  ToolShape shape;  // in the object frame O (origin at the shape's centre, as for the tool)
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();  // its pose at t = 0
  // Moved by a script: its pose at time t is the script's (CalcScriptedPose).
  std::optional<ScriptedTrajectory> script;
  // Touching it with the tool selects it; pressing the device button grabs it (VisualFrame).
  bool grabbable = false;
  // Dynamic: it falls under gravity and its contacts push it (contact/object_dynamics.h), with
  // this mass and body inertia about O's origin, which is its centre of mass (a mesh is
  // re-centred on it by config). A grabbed dynamic object moves with the tool and falls when
  // let go.
  bool dynamic = false;
  double mass_kg = 0.0;
  Eigen::Matrix3d inertia_O_kg_m2 = Eigen::Matrix3d::Zero();
  // Its own Coulomb μ under the friction law, for every contact with it (the tool's, the body's,
  // a grabbed object's); none: the scene's μ.
  std::optional<double> friction_coefficient;
};

// The object's pose at time t_s: the script's, or X_WO for an object without one.
Eigen::Isometry3d CalcScriptedPose(const RigidObject& object, double t_s);

// The object's bounding box in the world frame, at its pose X_WO.
Eigen::AlignedBox3d CalcWorldBox(const RigidObject& object);

class RigidObjectContacts {
 public:
  // Builds each object's distance field and feature points once, each object at its X_WO.
  // Throws std::invalid_argument for a bad shape (as ToolDistanceField does) or a negative margin.
  RigidObjectContacts(std::vector<RigidObject> objects, const ToolShape& tool, double margin_m);

  // Where object i is now, world (a scripted or grabbed object moves).
  void SetPose(int i, const Eigen::Isometry3d& X_WO);
  // Object i at X_WO_start, moving to X_WO_end within the frame: its contact thresholds widen by
  // its sweep bound, as the tool's do by the tool's.
  void SetMotion(int i, const Eigen::Isometry3d& X_WO_start, const Eigen::Isometry3d& X_WO_end);
  const Eigen::Isometry3d& pose(int i) const { return objects_[i].object.X_WO; }

  // Object i attached to the tool at X_TO (its pose in the tool frame), or none for i = −1.
  // The grabbed object's pose is still set by SetPose (the frame keeps it at X_WT X_TO).
  void SetGrabbed(int i, const Eigen::Isometry3d& X_TO = Eigen::Isometry3d::Identity());
  int grabbed() const { return grabbed_; }

  // Tool against every object but the grabbed one, and the grabbed object (moving with the tool)
  // against the others: appends contacts with on_tool = true and no body nodes.
  void AddToolContacts(const Eigen::Isometry3d& X_WT_start, const Eigen::Isometry3d& X_WT_end,
                       std::vector<Contact>* contacts) const;

  // Each dynamic object but the grabbed one against every other object but the grabbed one (whose
  // contacts are the tool's), each pair once: its sample points against the other's field and the
  // other's points against its own. Appends contacts with on_tool = false, rigid_object the
  // dynamic object (n_W out of it), other_object the other (contact/contact.h).
  void AddObjectContacts(std::vector<Contact>* contacts) const;

  // The nodes `surface_nodes` of a deformable body against every object: appends contacts with
  // one node of weight 1, on_tool = false except against the grabbed object, which sweeps with
  // the tool from X_WT_start to X_WT_end. x_start_m, x_end_m: (3N) node positions, world, m.
  void AddBodyContacts(const std::vector<int>& surface_nodes, const Eigen::VectorXd& x_start_m,
                       const Eigen::VectorXd& x_end_m, const Eigen::Isometry3d& X_WT_start,
                       const Eigen::Isometry3d& X_WT_end, std::vector<Contact>* contacts) const;

  // The deepest object containing p_W_m: its signed distance (< 0 inside; the smallest over the
  // objects, +inf without objects), closest surface point and outward normal, world.
  struct Penetration {
    int object = -1;  // which object, −1: none
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
    double sweep_m = 0.0;         // SetMotion's sweep bound (0 after SetPose)
  };
  // Appends the contact of tool point p_W (on the tool if radius 0, else the centre of a ball
  // of that radius) against object i when its gap is ≤ threshold_m.
  void AddPointContact(int i, const Eigen::Vector3d& p_W_m, double radius_m, double threshold_m,
                       std::vector<Contact>* contacts) const;
  // A body moving with the tool (the tool, of frame M = T, or the grabbed object, M = O) against
  // object i, both ways: its sample points against the object, the object's against its field.
  void AddMovingBodyContacts(const ToolDistanceField& field, const Matrix3Xd& points_M_m,
                             double point_radius_m, const Eigen::Isometry3d& X_WM, int i,
                             double threshold_m, std::vector<Contact>* contacts) const;
  // How far a point of the grabbed object can move in a tool motion from start to end, m.
  // (A body node's sweep is its own displacement; an object's, its sweep_m.)
  double CalcGrabbedSweep(const Eigen::Isometry3d& X_WT_start,
                          const Eigen::Isometry3d& X_WT_end) const;

  std::vector<Placed> objects_;
  ToolDistanceField tool_field_;
  Matrix3Xd tool_points_T_m_;  // (3 x K) the tool's sample points, T
  double tool_point_radius_m_ = 0.0;
  double margin_m_ = 0.0;
  int grabbed_ = -1;
  double grabbed_reach_m_ = 0.0;  // farthest point of the grabbed object from the tool's origin
};

}  // namespace hapsim::contact
