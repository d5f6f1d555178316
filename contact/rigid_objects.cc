#include "contact/rigid_objects.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace hapsim::contact {
namespace {

// The points a shape touches with, in its own frame, and the radius of the ball around each:
// a sphere's centre (radius r); a capsule's segment sampled at no more than r/2 (radius r); a
// cylinder with a rim rounded by e, which is a sharp cylinder (r − e, L − 2e) grown by e: that
// cylinder's rim points (radius e); the feature points of the others (radius 0: on the surface).
struct SamplePoints {
  Matrix3Xd points_m;
  double radius_m = 0.0;
};

SamplePoints MakeSamplePoints(const ToolShape& shape);

// A box's faces sampled inside: each face's centre and the four points halfway from it to the
// corners. A dynamic box rests on another box of its width face to face: its corners then sit on
// the other's edges, where the distance field's normal turns sideways (two equal cubes stacked
// fell through each other on corners alone); these points lie inside the other's face.
Matrix3Xd MakeBoxFacePoints(const Eigen::Vector3d& half_m) {
  Matrix3Xd points(3, 30);
  int k = 0;
  for (int axis = 0; axis < 3; ++axis)
    for (const double side : {-1.0, 1.0}) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (const auto& [su, sv] :
           {std::pair{0.0, 0.0}, {-0.5, -0.5}, {-0.5, 0.5}, {0.5, -0.5}, {0.5, 0.5}}) {
        Eigen::Vector3d p = Eigen::Vector3d::Zero();
        p[axis] = side * half_m[axis];
        p[u] = su * half_m[u];
        p[v] = sv * half_m[v];
        points.col(k++) = p;
      }
    }
  return points;
}

// The sample points of a rigid object: its shape's, and a dynamic box's face points.
SamplePoints MakeObjectSamplePoints(const RigidObject& object) {
  SamplePoints samples = MakeSamplePoints(object.shape);
  if (!object.dynamic || object.shape.kind != ToolShape::Kind::kBox) return samples;
  const Matrix3Xd faces = MakeBoxFacePoints(object.shape.half_extents_m);
  Matrix3Xd all(3, samples.points_m.cols() + faces.cols());
  all << samples.points_m, faces;
  samples.points_m = all;
  return samples;
}

SamplePoints MakeSamplePoints(const ToolShape& shape) {
  SamplePoints samples;
  if (shape.kind == ToolShape::Kind::kSphere) {
    samples.points_m = Matrix3Xd::Zero(3, 1);
    samples.radius_m = shape.radius_m;
  } else if (shape.kind == ToolShape::Kind::kCapsule) {
    // Spacing ≤ r/2, at most 1000 intervals (a needle-thin capsule then sinks by more than 3% of
    // r at a sharp edge, between samples).
    const double wanted = std::ceil(2.0 * shape.length_m / shape.radius_m);
    const int intervals = static_cast<int>(std::clamp(wanted, 1.0, 1000.0));
    samples.points_m = Matrix3Xd::Zero(3, intervals + 1);
    for (int k = 0; k <= intervals; ++k)
      samples.points_m(2, k) = shape.length_m * (static_cast<double>(k) / intervals - 0.5);
    samples.radius_m = shape.radius_m;
  } else if (shape.kind == ToolShape::Kind::kCylinder && shape.edge_radius_m > 0.0) {
    ToolShape inner = shape;
    inner.radius_m -= shape.edge_radius_m;
    inner.length_m -= 2.0 * shape.edge_radius_m;
    inner.edge_radius_m = 0.0;
    samples.points_m = MakeToolFeatures(inner).vertices_T_m;
    samples.radius_m = shape.edge_radius_m;
  } else {
    samples.points_m = MakeToolFeatures(shape).vertices_T_m;
  }
  return samples;
}

// Bounding box of the shape in its own frame.
Eigen::AlignedBox3d CalcLocalBox(const ToolShape& shape) {
  Eigen::Vector3d half = Eigen::Vector3d::Zero();
  switch (shape.kind) {
    case ToolShape::Kind::kSphere:
      half.setConstant(shape.radius_m);
      break;
    case ToolShape::Kind::kCapsule:
      half = {shape.radius_m, shape.radius_m, 0.5 * shape.length_m + shape.radius_m};
      break;
    case ToolShape::Kind::kCylinder:
      half = {shape.radius_m, shape.radius_m, 0.5 * shape.length_m};
      break;
    case ToolShape::Kind::kBox:
      half = shape.half_extents_m;
      break;
    case ToolShape::Kind::kMesh: {
      Eigen::AlignedBox3d box;
      for (int v = 0; v < shape.mesh.vertices_m.cols(); ++v)
        box.extend(shape.mesh.vertices_m.col(v));
      return box;
    }
  }
  return Eigen::AlignedBox3d(-half, half);
}

Eigen::AlignedBox3d TransformBox(const Eigen::AlignedBox3d& box_O, const Eigen::Isometry3d& X_WO) {
  Eigen::AlignedBox3d box_W;
  for (int corner = 0; corner < 8; ++corner)
    box_W.extend(X_WO * box_O.corner(static_cast<Eigen::AlignedBox3d::CornerType>(corner)));
  return box_W;
}

// The sweep bound of a body turning by the rotation from R_start to R_end and moving by Δx:
// |Δx| + θ R, R its farthest point from the origin of the motion.
double CalcSweep(const Eigen::Isometry3d& X_start, const Eigen::Isometry3d& X_end, double reach_m) {
  const double angle_rad = Eigen::AngleAxisd(X_start.linear().transpose() * X_end.linear()).angle();
  return (X_end.translation() - X_start.translation()).norm() + angle_rad * reach_m;
}

}  // namespace

Eigen::Isometry3d CalcScriptedPose(const RigidObject& object, double t_s) {
  if (!object.script) return object.X_WO;
  const DeviceState pose = object.script->Sample(t_s);
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
  X_WO.linear() = pose.q_WD.toRotationMatrix();
  X_WO.translation() = pose.x_W_m;
  return X_WO;
}

Eigen::AlignedBox3d CalcWorldBox(const RigidObject& object) {
  return TransformBox(CalcLocalBox(object.shape), object.X_WO);
}

RigidObjectContacts::RigidObjectContacts(std::vector<RigidObject> objects, const ToolShape& tool,
                                         double margin_m)
    : tool_field_(tool), margin_m_(margin_m) {
  if (!(margin_m >= 0.0)) throw std::invalid_argument("RigidObjectContacts: margin must be >= 0");
  const SamplePoints tool_samples = MakeSamplePoints(tool);
  tool_points_T_m_ = tool_samples.points_m;
  tool_point_radius_m_ = tool_samples.radius_m;
  objects_.reserve(objects.size());
  for (RigidObject& object : objects) {
    ToolDistanceField field(object.shape);
    SamplePoints samples = MakeObjectSamplePoints(object);
    const Eigen::AlignedBox3d box_W = CalcWorldBox(object);
    objects_.push_back(Placed{std::move(object), std::move(field), std::move(samples.points_m),
                              samples.radius_m, box_W});
  }
}

void RigidObjectContacts::AddPointContact(int i, const Eigen::Vector3d& p_W_m, double radius_m,
                                          double threshold_m,
                                          std::vector<Contact>* contacts) const {
  const Placed& placed = objects_[i];
  if (placed.box_W_m.exteriorDistance(p_W_m) > threshold_m + radius_m) return;
  const Eigen::Isometry3d& X_WO = placed.object.X_WO;
  const ToolDistance d = placed.field.Calc(X_WO.inverse() * p_W_m);
  const double gap_m = d.distance_m - radius_m;
  if (gap_m > threshold_m) return;
  const Eigen::Vector3d m_W = X_WO.linear() * d.normal_T;  // out of the object
  Contact contact;
  contact.n_W = -m_W;  // out of the tool, towards the object
  contact.p_tool_W_m = p_W_m - radius_m * m_W;
  contact.p_body_W_m = X_WO * d.closest_T_m;
  contact.gap_m = gap_m;
  contact.rigid_object = i;
  contacts->push_back(contact);
}

void RigidObjectContacts::SetPose(int i, const Eigen::Isometry3d& X_WO) {
  Placed& placed = objects_[i];
  placed.object.X_WO = X_WO;
  placed.box_W_m = CalcWorldBox(placed.object);
  placed.sweep_m = 0.0;
}

void RigidObjectContacts::SetMotion(int i, const Eigen::Isometry3d& X_WO_start,
                                    const Eigen::Isometry3d& X_WO_end) {
  SetPose(i, X_WO_start);
  Placed& placed = objects_[i];
  placed.sweep_m = CalcSweep(X_WO_start, X_WO_end, placed.field.bounding_radius_m());
}

void RigidObjectContacts::SetGrabbed(int i, const Eigen::Isometry3d& X_TO) {
  grabbed_ = i;
  grabbed_reach_m_ = 0.0;
  if (i < 0) return;
  const Eigen::AlignedBox3d box_O = CalcLocalBox(objects_[i].object.shape);
  for (int corner = 0; corner < 8; ++corner)
    grabbed_reach_m_ = std::max(
        grabbed_reach_m_,
        (X_TO * box_O.corner(static_cast<Eigen::AlignedBox3d::CornerType>(corner))).norm());
}

double RigidObjectContacts::CalcGrabbedSweep(const Eigen::Isometry3d& X_WT_start,
                                             const Eigen::Isometry3d& X_WT_end) const {
  return CalcSweep(X_WT_start, X_WT_end, grabbed_reach_m_);
}

void RigidObjectContacts::AddMovingBodyContacts(const ToolDistanceField& field,
                                                const Matrix3Xd& points_M_m, double point_radius_m,
                                                const Eigen::Isometry3d& X_WM, int i,
                                                double threshold_m,
                                                std::vector<Contact>* contacts) const {
  // The moving body's sample points against the object.
  for (int k = 0; k < points_M_m.cols(); ++k)
    AddPointContact(i, X_WM * points_M_m.col(k), point_radius_m, threshold_m, contacts);
  // The object's sample points against the moving body.
  const Placed& placed = objects_[i];
  const Eigen::Isometry3d X_MW = X_WM.inverse();
  const double reach_m = field.bounding_radius_m() + threshold_m + placed.point_radius_m;
  for (int k = 0; k < placed.points_O_m.cols(); ++k) {
    const Eigen::Vector3d s_W = placed.object.X_WO * placed.points_O_m.col(k);
    const Eigen::Vector3d s_M = X_MW * s_W;
    if (s_M.norm() > reach_m) continue;  // beyond the body's bounding sphere: no contact
    const ToolDistance d = field.Calc(s_M);
    const double gap_m = d.distance_m - placed.point_radius_m;
    if (gap_m > threshold_m) continue;
    Contact contact;
    contact.n_W = X_WM.linear() * d.normal_T;  // out of the moving body
    contact.p_tool_W_m = X_WM * d.closest_T_m;
    contact.p_body_W_m = s_W - placed.point_radius_m * contact.n_W;
    contact.gap_m = gap_m;
    contact.rigid_object = i;
    contacts->push_back(contact);
  }
}

void RigidObjectContacts::AddToolContacts(const Eigen::Isometry3d& X_WT_start,
                                          const Eigen::Isometry3d& X_WT_end,
                                          std::vector<Contact>* contacts) const {
  const double tool_threshold_m =
      margin_m_ + CalcSweep(X_WT_start, X_WT_end, tool_field_.bounding_radius_m());
  const double grabbed_threshold_m = margin_m_ + CalcGrabbedSweep(X_WT_start, X_WT_end);
  for (int i = 0; i < num_objects(); ++i) {
    if (i == grabbed_) continue;  // attached to the tool: no contact between them
    const double object_sweep_m = objects_[i].sweep_m;
    AddMovingBodyContacts(tool_field_, tool_points_T_m_, tool_point_radius_m_, X_WT_start, i,
                          tool_threshold_m + object_sweep_m, contacts);
    if (grabbed_ >= 0) {
      const Placed& grabbed = objects_[grabbed_];
      AddMovingBodyContacts(grabbed.field, grabbed.points_O_m, grabbed.point_radius_m,
                            grabbed.object.X_WO, i, grabbed_threshold_m + object_sweep_m, contacts);
    }
  }
}

void RigidObjectContacts::AddObjectContacts(std::vector<Contact>* contacts) const {
  for (int i = 0; i < num_objects(); ++i) {
    const Placed& moving = objects_[i];
    if (!moving.object.dynamic || i == grabbed_) continue;
    for (int j = 0; j < num_objects(); ++j) {
      if (j == i || j == grabbed_ || (objects_[j].object.dynamic && j < i)) continue;
      const size_t first = contacts->size();
      AddMovingBodyContacts(moving.field, moving.points_O_m, moving.point_radius_m,
                            moving.object.X_WO, j, margin_m_ + moving.sweep_m + objects_[j].sweep_m,
                            contacts);
      for (size_t k = first; k < contacts->size(); ++k) {
        Contact& contact = (*contacts)[k];
        contact.on_tool = false;  // the moving side is object i, not the tool
        contact.rigid_object = i;
        contact.other_object = j;
      }
    }
  }
}

void RigidObjectContacts::AddBodyContacts(const std::vector<int>& surface_nodes,
                                          const Eigen::VectorXd& x_start_m,
                                          const Eigen::VectorXd& x_end_m,
                                          const Eigen::Isometry3d& X_WT_start,
                                          const Eigen::Isometry3d& X_WT_end,
                                          std::vector<Contact>* contacts) const {
  for (int i = 0; i < num_objects(); ++i) {
    const Placed& placed = objects_[i];
    const Eigen::Isometry3d X_OW = placed.object.X_WO.inverse();
    const bool grabbed = i == grabbed_;
    const double object_sweep_m = grabbed ? CalcGrabbedSweep(X_WT_start, X_WT_end) : placed.sweep_m;
    for (const int node : surface_nodes) {
      const Eigen::Vector3d x_W = x_start_m.segment<3>(3 * node);
      const double threshold_m =
          margin_m_ + (x_end_m.segment<3>(3 * node) - x_W).norm() + object_sweep_m;
      if (placed.box_W_m.exteriorDistance(x_W) > threshold_m) continue;
      const ToolDistance d = placed.field.Calc(X_OW * x_W);
      if (d.distance_m > threshold_m) continue;
      Contact contact;
      contact.on_tool = grabbed;  // the grabbed object is part of the tool
      contact.rigid_object = i;
      contact.n_W = placed.object.X_WO.linear() * d.normal_T;  // out of the object (and tool)
      contact.p_tool_W_m = placed.object.X_WO * d.closest_T_m;
      contact.p_body_W_m = x_W;
      contact.gap_m = d.distance_m;
      contact.SetBodyNodes({node}, {1.0});
      contacts->push_back(contact);
    }
  }
}

RigidObjectContacts::Penetration RigidObjectContacts::CalcDeepest(
    const Eigen::Vector3d& p_W_m) const {
  Penetration deepest;
  deepest.distance_m = std::numeric_limits<double>::infinity();
  for (int i = 0; i < num_objects(); ++i) {
    const Placed& placed = objects_[i];
    if (placed.box_W_m.exteriorDistance(p_W_m) > 0.0) continue;  // outside: d > 0
    const ToolDistance d = placed.field.Calc(placed.object.X_WO.inverse() * p_W_m);
    if (d.distance_m >= deepest.distance_m) continue;
    deepest.object = i;
    deepest.distance_m = d.distance_m;
    deepest.closest_W_m = placed.object.X_WO * d.closest_T_m;
    deepest.normal_W = placed.object.X_WO.linear() * d.normal_T;
  }
  return deepest;
}

}  // namespace hapsim::contact
