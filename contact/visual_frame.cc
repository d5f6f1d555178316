#include "contact/visual_frame.h"

#include <Eigen/Dense>
#include <algorithm>
#include <optional>
#include <stdexcept>

#include "core/stopwatch.h"

namespace hapsim::contact {
namespace {

// c = J_v v + J_ω ω + J_u u̇ for every row.
Eigen::VectorXd CalcSeparatingVelocity(const ContactJacobian& J, const Eigen::Vector3d& v_W_m_s,
                                       const Eigen::Vector3d& w_W_rad_s,
                                       const Eigen::VectorXd& u_dot_m_s) {
  return J.J_v * v_W_m_s + J.J_w * w_W_rad_s + J.J_u * u_dot_m_s;
}

}  // namespace

const char* ToString(ComplianceMethod method) {
  return method == ComplianceMethod::kExact ? "exact" : "warped";
}

const char* ToString(ModelComplianceStep step) {
  switch (step) {
    case ModelComplianceStep::kVisual:
      return "visual";
    case ModelComplianceStep::kHaptic:
      return "haptic";
    case ModelComplianceStep::kAuto:
      return "auto";
  }
  return "?";
}

VisualFrame::VisualFrame(const fem::Model& body, const fem::FemOptions& fem_options,
                         Eigen::VectorXd body_external_force_N, ToolModel tool,
                         const VisualFrameOptions& options)
    : VisualFrame(&body, &fem_options, std::move(body_external_force_N), std::move(tool), options) {
}

VisualFrame::VisualFrame(const fem::Model* body, const fem::FemOptions* fem_options,
                         Eigen::VectorXd body_external_force_N, ToolModel tool,
                         const VisualFrameOptions& options)
    : body_(body),
      tool_(std::move(tool)),
      options_(options),
      rows_per_contact_(options.response.solve.law == ContactLaw::kFriction ? 3 : 1),
      objects_have_own_friction_(
          options.response.solve.law == ContactLaw::kFriction &&
          std::any_of(options.rigid_objects.begin(), options.rigid_objects.end(),
                      [](const RigidObject& o) { return o.friction_coefficient.has_value(); })),
      impulse_start_(rows_per_contact_),
      rigid_contacts_(options.rigid_objects, tool_.shape, options.detection.margin_m) {
  for (size_t i = 0; i < options.rigid_objects.size(); ++i)
    if (options.rigid_objects[i].dynamic)
      dynamic_objects_.push_back(MakeDynamicObject(static_cast<int>(i), options.rigid_objects[i]));
  if (!(options.sanity_tolerance_m > 0.0))
    throw std::invalid_argument("VisualFrame: sanity_tolerance_m must be positive");
  if ((body == nullptr) != (fem_options == nullptr))
    throw std::invalid_argument("VisualFrame: give both the body and its FEM options, or neither");
  if (body_ != nullptr) {
    stepper_ = std::make_unique<fem::TimeStepper>(*body, *fem_options, options.dt_s,
                                                  std::move(body_external_force_N));
    detector_ = std::make_unique<CollisionDetector>(*body, tool_.shape, options.detection);
    if (options.compliance == ComplianceMethod::kWarped)
      warped_compliance_ = std::make_unique<fem::WarpedCompliance>(*body, *stepper_);
    if (options.model_compliance_step == ModelComplianceStep::kHaptic) {
      haptic_stepper_ = std::make_unique<fem::TimeStepper>(*body, *fem_options, options.haptic_dt_s,
                                                           stepper_->external_force_N());
      haptic_compliance_ = std::make_unique<fem::WarpedCompliance>(*body, *haptic_stepper_);
    }
    // A fixed node cannot move: its row with an object, or a grasp's, would be all zero.
    if (!options.rigid_objects.empty() || options.grasp)
      surface_nodes_ = fem::FindFreeSurfaceNodes(*body);
    body_contacts_ = std::make_unique<BodyBodyContacts>(*body, options.detection.margin_m);
    if (body_contacts_->num_objects() < 2) body_contacts_.reset();
    if (options.grasp) {
      if (rows_per_contact_ != 1)
        throw std::invalid_argument(
            "VisualFrame: a grasp needs normal rows (not the friction law)");
      if (!body->collision_surface.empty())
        throw std::invalid_argument(
            "VisualFrame: a grasp holds the tets' boundary nodes, not an embedded collision "
            "surface's points");
      grasp_ = std::make_unique<TissueGrasp>(*options.grasp, surface_nodes_, body->num_nodes());
    }
  } else if (options.grasp) {
    throw std::invalid_argument("VisualFrame: a grasp needs a deformable body to hold");
  }
}

VisualFrameStats VisualFrame::Step(const DeviceState& device, fem::State* body, ToolState* tool,
                                   const ToolState* haptic_tool) {
  VisualFrameStats stats;
  Stopwatch total, stage;
  // 1. Virtual coupling between the device and the visual tool.
  wrench_ = CalcCouplingWrench(options_.coupling, device, *tool, CalcAngularVelocity(tool_, *tool));
  stats.coupling_s = stage.Lap();
  // 2. Collision-free tool update (linearised implicit Euler).
  tool_system_ = CalcToolStepSystem(tool_, *tool, wrench_, options_.gravity_m_s2, options_.dt_s);
  CalcFreeVelocityChange(tool_system_, &dv_tool_, &dL_tool_);
  stats.free_tool_s = stage.Lap();
  // 3. Collision-free FEM update. CG starts from the last frame's free change (its total less
  //    the contact correction): under a steady press the total is near zero while the free
  //    change is not (the body would spring back), and on block_press this start saves one CG
  //    iteration in seven.
  if (stepper_) {
    if (du_contact_.size() == du_body_.size()) du_body_ -= du_contact_;
    stats.fem = stepper_->CalcFreeVelocityChange(*body, &du_body_);
  }
  stats.free_fem_s = stage.Lap();
  // 4. Collision detection, swept from the start to the free configuration, with the rigid
  //    objects placed for the frame and the grasper's jaws opened or closed (the button is read
  //    once a frame, at its start).
  const bool button_down = (device.buttons & 1) != 0;
  const bool pressed = button_down && !button_was_down_;
  button_was_down_ = button_down;
  MoveRigidObjects(button_down, pressed, *tool);
  UpdateGrasp(button_down, pressed, *tool, *body, &stats);
  DetectContacts(*body, *tool);
  stats.num_candidates = static_cast<int>(contacts_.size());
  for (const Contact& contact : contacts_) stats.num_rigid_contacts += contact.rigid_object >= 0;
  stats.detection_s = stage.Lap();
  // 5. Constraint solve and post-collision state of tool and body.
  SolveResponse(*tool, *body, &stats);
  stats.solve = last_solve_;
  const Eigen::Isometry3d X_WT_start = CalcPose(*tool);
  AdvanceTool(tool_, options_.dt_s, dv_tool_, dL_tool_, tool);
  if (stepper_) stepper_->Advance(du_body_, body);
  FinishRigidObjects(*tool);
  stats.num_contacts = static_cast<int>(contacts_.size());
  for (int row = 0; row < lambda_.size(); row += rows_per_contact_)
    stats.num_active += lambda_[row] > 0.0 && !contacts_[row / rows_per_contact_].bilateral;
  if (grasp_) {
    // The grip: points pulled past its limit slip out; their rows leave the model below.
    stats.num_grasp_slipped = grasp_->LetSlip(contacts_, lambda_);
    stats.num_grasped = static_cast<int>(grasp_->held_nodes().size());
  }
  stats.response_s = stage.Lap();
  // 6. Linear contact model for the haptic step, at the post-collision state.
  BuildLinearModel(device, X_WT_start, *tool, haptic_tool ? *haptic_tool : *tool, *body);
  stats.model_s = stage.Lap();
  // 7. Sanity pass: nodes still inside the tool are moved to its surface.
  stats.num_sanity_corrections =
      RunSanityPass(*tool, body, &stats.max_penetration_m, &stats.max_object_penetration_m);
  // Held points back where the jaws hold them. After the model, which is linearised at the state
  // the response left, as for the tool's contacts: putting them back first (the model's grasp
  // gaps then 0) took retraction's pull 0.0042 → 0.0099 N RMS from the reference's.
  if (grasp_)
    stats.max_grasp_drift_m = grasp_->MoveHeldPointsToTheJaws(CalcPose(*tool), tool->v_W_m_s,
                                                              CalcAngularVelocity(tool_, *tool),
                                                              &body->x_m, &body->v_m_s);
  stats.sanity_s = stage.Lap();
  stats.total_s = total.Elapsed();
  ++frame_index_;
  return stats;
}

void VisualFrame::UpdateGrasp(bool button_down, bool pressed, const ToolState& tool,
                              const fem::State& body, VisualFrameStats* stats) {
  if (!grasp_) return;
  if (!button_down) {
    grasp_->Open();
  } else if (pressed) {
    stats->grasp_closed_now = true;
    stats->num_grasp_taken = grasp_->Close(CalcPose(tool), body.x_m);
  }
}

// Tool against body, then tool against the rigid objects, then body against them, then the
// body's objects against each other, then the grasp's rows: one list, one response.
void VisualFrame::DetectContacts(const fem::State& body, const ToolState& tool) {
  ToolState tool_end = tool;
  AdvanceTool(tool_, options_.dt_s, dv_tool_, dL_tool_, &tool_end);
  contacts_.clear();
  Eigen::VectorXd x_end_m;
  if (body_ != nullptr) {
    x_end_m = body.x_m + options_.dt_s * (body.v_m_s + du_body_);
    detector_->Detect(body.x_m, CalcPose(tool), x_end_m, CalcPose(tool_end), &contacts_);
  }
  rigid_contacts_.AddToolContacts(CalcPose(tool), CalcPose(tool_end), &contacts_);
  rigid_contacts_.AddObjectContacts(&contacts_);
  if (body_ != nullptr)
    rigid_contacts_.AddBodyContacts(surface_nodes_, body.x_m, x_end_m, CalcPose(tool),
                                    CalcPose(tool_end), &contacts_);
  if (body_contacts_) body_contacts_->AddContacts(body.x_m, x_end_m, &contacts_);
  if (grasp_) {
    grasp_->DropToolContactsOnHeldPoints(&contacts_);
    grasp_->AddContacts(CalcPose(tool), body.x_m, &contacts_);
  }
}

ContactJacobian VisualFrame::CalcJacobian(const std::vector<Contact>& contacts,
                                          const Eigen::Vector3d& x_tool_W_m) const {
  static const std::vector<std::uint8_t> kNoDofs;
  return CalcContactJacobian(contacts, x_tool_W_m, rows_per_contact_, body_ ? body_->num_dofs() : 0,
                             body_ ? body_->dof_is_fixed : kNoDofs);
}

void VisualFrame::SolveResponse(const ToolState& tool, const fem::State& body,
                                VisualFrameStats* stats) {
  const double dt = options_.dt_s;
  const Eigen::Vector3d v_free = tool.v_W_m_s + dv_tool_;
  const Eigen::Vector3d w_free = tool_system_.M_inv_W * (tool.L_W_kg_m2_s + dL_tool_);
  const Eigen::VectorXd u_free = body.v_m_s + du_body_;
  jacobian_ = CalcJacobian(contacts_, tool.x_W_m);
  Eigen::VectorXd c_free = CalcSeparatingVelocity(jacobian_, v_free, w_free, u_free);
  // Rigid objects refuse the equality law (config/scene.cc), so its selection never meets a
  // moving object: c_object is zero there.
  if (options_.response.solve.law == ContactLaw::kEquality) {
    std::vector<Contact> colliding;
    for (int i : SelectCollidingContacts(contacts_, c_free, rows_per_contact_, dt, 0.0))
      colliding.push_back(contacts_[i]);
    contacts_.swap(colliding);
    jacobian_ = CalcJacobian(contacts_, tool.x_W_m);
    c_free = CalcSeparatingVelocity(jacobian_, v_free, w_free, u_free);
  }
  CalcObjectVelocities();
  const Eigen::VectorXd c_object = CalcObjectSeparatingVelocity(contacts_);
  c_free += c_object;
  Eigen::VectorXd c_pre =
      CalcSeparatingVelocity(jacobian_, tool.v_W_m_s, tool_system_.M_inv_W * tool.L_W_kg_m2_s,
                             body.v_m_s) +
      c_object;
  // The dynamic objects' own velocities, through their rows (their motion is not in c_object).
  for (DynamicObject& object : dynamic_objects_) {
    if (!IsFreeDynamicObject(object.object)) continue;
    SetObjectRows(contacts_, rows_per_contact_, &object);
    AddObjectSeparatingVelocity(object, /*free=*/true, &c_free);
    AddObjectSeparatingVelocity(object, /*free=*/false, &c_pre);
  }
  b_ = CalcConstraintTargets(contacts_, c_pre, rows_per_contact_, dt, options_.response);
  const int num_rows = jacobian_.num_rows();
  Stopwatch stage;
  SetBodyCompliance(num_rows);
  stats->compliance_s = stage.Lap();
  W_.SetAbove(&W_body_);
  W_.AddRigidPart(jacobian_, tool_system_);
  if (rows_per_contact_ == 3) SetFrictionCoefficients();
  const bool warm = options_.response.solve.law != ContactLaw::kEquality;
  lambda_ = warm ? impulse_start_.Start(contacts_) : Eigen::VectorXd::Zero(num_rows);
  bilateral_rows_.assign(static_cast<size_t>(num_rows), 0);
  for (size_t i = 0; i < contacts_.size(); ++i)
    if (contacts_[i].bilateral) bilateral_rows_[rows_per_contact_ * i] = 1;
  if (options_.response.solve.law == ContactLaw::kUnilateral)
    last_solve_ = SolveUnilateralByColumns(
        W_.W(), W_.diagonal(), [this](const std::vector<Eigen::Index>& c) { W_.Fill(c); },
        b_ - c_free, dt, options_.response.solve, &lambda_, grasp_ ? &bilateral_rows_ : nullptr);
  else
    last_solve_ =
        SolveContactImpulses(W_.W(), b_ - c_free, dt, rows_per_contact_, options_.response.solve,
                             &lambda_, objects_have_own_friction_ ? &mu_per_contact_ : nullptr,
                             grasp_ ? &bilateral_rows_ : nullptr);
  if (warm) impulse_start_.Record(contacts_, lambda_);
  stats->solve_s = stage.Lap();
  // Post-collision: A Δv = Δt (F̃ + Jᵀλ) for each body, i.e. the free change plus the impulse's.
  dv_tool_ += tool_system_.A_v.inverse() * (dt * jacobian_.J_v.transpose() * lambda_);
  dL_tool_ += tool_system_.A_L.inverse() * (dt * jacobian_.J_w.transpose() * lambda_);
  if (num_rows > 0 && stepper_) {
    // Warm start from the previous frame's contact correction: a press changes it slowly, and
    // on block_press this saves about one CG iteration in four.
    if (du_contact_.size() != body_->num_dofs()) du_contact_.setZero(body_->num_dofs());
    stepper_->SolveWithSystemMatrix(dt * (jacobian_.J_u.transpose() * lambda_),
                                    stepper_->has_free_object()
                                        ? options_.free_body_correction_relative_tolerance
                                        : options_.correction_relative_tolerance,
                                    &du_contact_);
    du_body_ += du_contact_;
  } else {
    du_contact_.resize(0);  // nothing was added to du_body_: nothing to take off next frame
  }
  stats->correction_s = stage.Lap();
  c_post_ = c_free + dt * MultiplyByImpulses(W_.W(), lambda_);  // columns of λ ≠ 0: formed
}

// W_body (and the haptic step's) of the frame's rows, with the free dynamic objects' parts. Under
// the unilateral law every reader of W needs only some of its columns (frame_compliance.h): it is
// formed by columns there, whole otherwise.
void VisualFrame::SetBodyCompliance(int num_rows) {
  const bool by_columns = options_.response.solve.law == ContactLaw::kUnilateral;
  // The rows rotated once for both compliances (they differ in A₀ alone): block_press, frames
  // with ≥ 200 contacts, 0.11 → 0.07 ms for the two (docs/BENCHMARKS.md, ninth pass).
  std::optional<fem::WarpedCompliance::RotatedRows> rotated;
  if (stepper_ && (warped_compliance_ || haptic_compliance_)) {
    fem::WarpedCompliance& any = warped_compliance_ ? *warped_compliance_ : *haptic_compliance_;
    rotated = any.RotateRows(jacobian_.J_u, stepper_->rotations());
  }
  if (!stepper_) {
    W_body_.SetWhole(Eigen::MatrixXd::Zero(num_rows, num_rows));  // rigid objects only
  } else if (warped_compliance_) {
    warped_compliance_->SetRows(*rotated);
    if (by_columns)
      W_body_.SetByColumns(warped_compliance_.get(), num_rows);
    else
      W_body_.SetWhole(warped_compliance_->CalcAll());
  } else {
    W_body_.SetWhole(stepper_->CalcCompliance(jacobian_.J_u));
  }
  if (haptic_compliance_) {
    haptic_compliance_->SetRows(*rotated);
    if (by_columns)
      W_body_haptic_.SetByColumns(haptic_compliance_.get(), num_rows);
    else
      W_body_haptic_.SetWhole(haptic_compliance_->CalcAll());
  }
  for (const DynamicObject& object : dynamic_objects_) {
    if (!IsFreeDynamicObject(object.object)) continue;
    W_body_.AddRigidPart(object.J, object.system);  // a rigid body: the same at either step
    if (haptic_compliance_) W_body_haptic_.AddRigidPart(object.J, object.system);
  }
}

void VisualFrame::SetFrictionCoefficients() {
  // μ of a contact with an object is that object's (its own or the scene's); the grabbed object
  // pressing another takes the other's, as the tool touching it would; of two objects touching,
  // the dynamic one's own, else the other's own. Kept for the lcp rows.
  mu_per_contact_.setConstant(static_cast<Eigen::Index>(contacts_.size()),
                              options_.response.solve.friction_coefficient);
  for (size_t i = 0; i < contacts_.size(); ++i) {
    for (const int object : {contacts_[i].other_object, contacts_[i].rigid_object})
      if (object >= 0 && options_.rigid_objects[object].friction_coefficient)
        mu_per_contact_[static_cast<Eigen::Index>(i)] =
            *options_.rigid_objects[object].friction_coefficient;
  }
}

Eigen::VectorXd VisualFrame::MultiplyByImpulses(const Eigen::MatrixXd& W,
                                                const Eigen::VectorXd& lambda) {
  Eigen::VectorXd product = Eigen::VectorXd::Zero(W.rows());
  for (Eigen::Index c = 0; c < lambda.size(); ++c)
    if (lambda[c] != 0.0) product.noalias() += lambda[c] * W.col(c);
  return product;
}

Eigen::Vector3d VisualFrame::contact_force_N() const { return jacobian_.J_v.transpose() * lambda_; }

Eigen::Vector3d VisualFrame::contact_torque_N_m() const {
  return jacobian_.J_w.transpose() * lambda_;
}

}  // namespace hapsim::contact
