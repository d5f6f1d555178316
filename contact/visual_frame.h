#pragma once
// One frame of the visual process (DESIGN.md §1), the seven stages in order:
//   1 coupling to the visual tool   2 free tool update   3 free FEM update
//   4 collision detection           5 constraint solve + post-collision state
//   6 linear contact model          7 sanity pass on nodes left inside the tool
// Stage 4 finds the tool against the body, the tool and the body against rigid objects, and the
// body's objects against each other (contact/body_body_contacts.h).
// Step() reads top to bottom as that pipeline. Model data (body model, tool model, rigid objects,
// options) is fixed at construction; the body and tool states are passed in and updated.
// A scene without a deformable body (DESIGN.md §9: rigid objects only) builds no FEM: stage 3 does
// nothing, the body state is empty (no dofs), and every contact row is the tool against a rigid
// object.
//
// Rigid objects that move (visual_frame_objects.cc), placed at the start of stage 4:
//   scripted: at the script's pose at the frame's start t_k = k Δt, moving to the pose at t_k + Δt
//     with the mean velocity of that motion. The velocity enters each of its rows as a constant
//     separating velocity, c = J_v v + J_ω ω + J_u u̇ + c_object (the gap's rate is the relative
//     velocity of the two sides along the row), so a moving constraint is held at velocity
//     level like a fixed one, with no lag of a penetration behind the object.
//   grabbed (paper 003): a grabbable object is selected while the tool touches it (a contact
//     within the detection margin at a frame's end); a press of the device's button 0 attaches
//     the selected object to the tool at its pose relative to the tool then (X_TO), and it moves
//     as part of the tool until the button is released, where it stays. The button is read once
//     a frame: a press shorter than a frame may be missed. Frames count from 0 at
//     construction: Step k is the frame [k Δt, (k + 1) Δt].
//   dynamic (contact/object_dynamics.h): takes its free step under gravity first, is placed at
//     the frame's start swept to the free step's end, and touches the other objects too; its
//     velocity and compliance enter the one solve through its rows, and it ends the frame where
//     the solve's impulses leave it. Grabbed, it moves with the tool as above; let go, it keeps
//     the tool's motion and falls.
//   The same press closes a grasper's jaws on the body (options.grasp, contact/tissue_grasp.h):
//     the surface points inside them are held by bilateral rows from that frame on, added to the
//     frame's contacts after detection, until the button is released or a point's grip force
//     passes its limit.

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <vector>

#include "contact/body_body_contacts.h"
#include "contact/collision_detection.h"
#include "contact/collision_response.h"
#include "contact/contact_jacobian.h"
#include "contact/frame_compliance.h"
#include "contact/haptic_contact_rows.h"
#include "contact/impulse_warm_start.h"
#include "contact/linear_contact_model.h"
#include "contact/object_dynamics.h"
#include "contact/rigid_objects.h"
#include "contact/tissue_grasp.h"
#include "core/rigid_tool.h"
#include "core/tool_integrator.h"
#include "core/virtual_coupling.h"
#include "fem/model.h"
#include "fem/state.h"
#include "fem/time_stepper.h"
#include "fem/warped_compliance.h"

namespace hapsim::contact {

// How the response gets the body's compliance W_body = J_u A_u⁻¹ J_uᵀ (docs/CONTACT.md):
//   kExact   forward solves with the step's Cholesky factor (the lagged one under CG)
//   kWarped  a precomputed rest compliance warped by node rotations (fem/warped_compliance.h):
//            several times cheaper, exact at rest and under rigid motion
enum class ComplianceMethod { kExact, kWarped };
const char* ToString(ComplianceMethod method);

// Which step the linear contact model's body compliance is for (DESIGN.md §4's open question):
//   kVisual  the visual step's, W_body = J_u A_u(Δt_v)⁻¹ J_uᵀ, as the frame's own solve (the paper)
//   kHaptic  the haptic step's, J_u A_u(Δt_h)⁻¹ J_uᵀ with A_u(Δt) = M + Δt D + Δt² K: how far the
//            body yields within one haptic step under a force held over it. Warped from a rest
//            factor at Δt_h (fem/warped_compliance.h), whatever `compliance` the frame uses.
//   kAuto    chosen by the haptic mode and the visual rate (device::ResolveModelComplianceStep,
//            applied with the mode's other needs by device::SetUpFrameForMode; the frame takes
//            an unresolved one as kVisual)
// scripts/bench.sh measures both against the reference (docs/RESULTS.md).
enum class ModelComplianceStep { kVisual, kHaptic, kAuto };
const char* ToString(ModelComplianceStep step);

struct VisualFrameOptions {
  double dt_s = 1.0 / 30.0;   // visual step
  double haptic_dt_s = 1e-3;  // step the linear contact model is built for
  Eigen::Vector3d gravity_m_s2{0.0, 0.0, -9.81};
  CouplingParams coupling;
  DetectionOptions detection;
  ResponseOptions response;
  double sanity_tolerance_m = 1e-4;  // nodes (embedded points) deeper inside the tool move out
  ComplianceMethod compliance = ComplianceMethod::kWarped;
  // CG's relative tolerance for the contact correction A_u⁻¹ Δt J_uᵀ λ, or the scene's solver
  // tolerance where that is looser; 0: the scene's. Looser than the free step's 1e-6 because
  // W_body is itself ~1% off (warped) and an error here is one frame's velocity error, which the
  // next frame's constraint targets correct (docs/CONTACT.md "Response"). How loose depends on
  // what holds the body:
  // - Anchored (every object has a fixed dof): the support takes what the solve leaves. 1e-2:
  //   on block_press one CG iteration a frame fewer than 1e-4 (correction 0.52 → 0.30 ms at
  //   ≥ 200 contacts) and the device force against the reference 0.04003 against 0.04004 N RMS;
  //   a grasped block held 3 s rests to 2e-9 m/s either way (tissue_grasp_test). One fixed node
  //   counts: a body pinned at a point could still turn about it, which no shipped scene does
  //   (they fix a face).
  // - With a free object (resting on a plate or another object): 1e-4. Looser, what the solve
  //   leaves is an impulse the object never receives: at 1e-2 a block on a rising plate carried
  //   its weight 1.05 % short, and a cube on a free soft block, or a block stacked on another,
  //   still moved at 1.5–4.2e-4 m/s when it should rest (moving_objects_test,
  //   object_dynamics_test, body_body_contact_test; 2026-11-28). Translating each free object
  //   so that its residual's net force is zero (momentum then exact) fixed the weight but left
  //   2–3e-4 m/s; carrying the residual impulse into the next frame's free step grew a grasped
  //   block's rest velocity from 1e-9 to 3e-5 m/s over 12 s (a force delayed a frame). Neither
  //   was kept.
  double correction_relative_tolerance = 1e-2;
  double free_body_correction_relative_tolerance = 1e-4;
  ModelComplianceStep model_compliance_step = ModelComplianceStep::kVisual;
  // Stage 6 also exports the per-contact rows of every candidate contact for the haptic `lcp`
  // mode (contact_rows()): normal rows, or with the friction law three rows per contact and
  // each contact's μ.
  bool export_contact_rows = false;
  // Of those, only the active contacts and the ones an approach at this speed (m/s) beyond the
  // tool's present one could engage within the frame keep their coupling through the body; the
  // others travel with their own block of W_body alone (ExportContactRows). 0: all coupled.
  double lcp_reach_m_s = 0.0;
  // At most this many rows are exported (the haptic solver's capacity, haptic.lcp_max_rows): the
  // coupled ones, then the uncoupled contacts nearest to engaging. 0: no limit.
  int lcp_max_rows = 0;
  // The scene's fixed rigid objects (contact/rigid_objects.h). They are model data, kept here so
  // that every user of the frame (sim, run, the tests) gets them from the one scene mapping
  // (config::MakeVisualFrameOptions).
  std::vector<RigidObject> rigid_objects;
  // The tool's jaws (scene key tool.grasp), if it is a grasper; needs a body and normal rows
  // (the unilateral or equality law).
  std::optional<GraspOptions> grasp;
};

// Wall time of each stage, seconds, and what the frame found.
struct VisualFrameStats {
  double coupling_s = 0.0, free_tool_s = 0.0, free_fem_s = 0.0, detection_s = 0.0;
  double response_s = 0.0, model_s = 0.0, sanity_s = 0.0, total_s = 0.0;
  // Of response_s: the body's compliance W_body (both steps' when the model takes the haptic
  // step's); the impulse solve with forming W and the warm start; the post-collision correction
  // A_u⁻¹ Δt J_uᵀ λ with the tool's. The rest of response_s (the Jacobian, the targets, c_post)
  // is in none of the three. Where W is formed by columns (FrameCompliance), compliance_s is the
  // set-up and the diagonal, and the columns are formed within solve_s (the solve's) and model_s
  // (the model's and the lcp rows').
  double compliance_s = 0.0, solve_s = 0.0, correction_s = 0.0;
  int num_candidates = 0;      // contacts detected
  int num_contacts = 0;        // contacts made constraints
  int num_active = 0;          // constraints with λ > 0
  int num_rigid_contacts = 0;  // of the candidates: tool or body against a rigid object
  int num_sanity_corrections = 0;
  // The grasper (options.grasp): points held after the frame, taken when the jaws closed at its
  // start (closing on none is a grasp of nothing, which a caller should say), and let slip at its
  // end with a grip force past the limit.
  int num_grasped = 0;
  int num_grasp_taken = 0;
  bool grasp_closed_now = false;
  int num_grasp_slipped = 0;
  double max_grasp_drift_m = 0.0;  // the farthest a held point was put back to the jaws, m
  double max_penetration_m = 0.0;  // deepest contact node inside the tool after the step, ≥ 0
  // Deepest body node of a body–object contact inside its rigid object after the step, as the
  // sanity pass finds it before moving it out, ≥ 0.
  double max_object_penetration_m = 0.0;
  ContactSolveReport solve;
  fem::StepStats fem;
};

class VisualFrame {
 public:
  // `body` must outlive the frame. body_external_force_N (3N): gravity on the body and loads.
  VisualFrame(const fem::Model& body, const fem::FemOptions& fem_options,
              Eigen::VectorXd body_external_force_N, ToolModel tool,
              const VisualFrameOptions& options);
  // `body` and `fem_options` null: a scene without a deformable body, the tool among rigid
  // objects. Step() then takes an empty fem::State (fem::State{}).
  VisualFrame(const fem::Model* body, const fem::FemOptions* fem_options,
              Eigen::VectorXd body_external_force_N, ToolModel tool,
              const VisualFrameOptions& options);

  // `haptic_tool`, if given, is the haptic loop's instance of the tool: the linear contact model is
  // then linearised at its state (coupling, tool matrices, and gaps shifted by its offset from
  // the visual tool), so that the haptic tool's drift from the visual one is corrected every frame.
  VisualFrameStats Step(const DeviceState& device, fem::State* body, ToolState* tool,
                        const ToolState* haptic_tool = nullptr);

  // Results of the last Step.
  const LinearContactModel& linear_model() const { return linear_model_; }
  // Rows of the frame's contacts, linearised as the model is (empty unless
  // options.export_contact_rows): every candidate, the coupled contacts first.
  const ContactRows& contact_rows() const { return contact_rows_; }
  const std::vector<Contact>& contacts() const { return contacts_; }
  const ContactJacobian& jacobian() const { return jacobian_; }
  const Eigen::VectorXd& impulses() const { return lambda_; }  // λ per row, N
  // Contact force on the tool, J_vᵀλ, and torque J_ωᵀλ of the last frame, world.
  Eigen::Vector3d contact_force_N() const;
  Eigen::Vector3d contact_torque_N_m() const;
  const ToolModel& tool_model() const { return tool_; }
  bool has_body() const { return body_ != nullptr; }
  // The rigid objects after the last Step (scripted ones at the frame's end, a grabbed one with
  // the tool), and the grabbable object the tool touches (selected) or holds (grabbed); −1: none.
  int num_objects() const { return rigid_contacts_.num_objects(); }
  const Eigen::Isometry3d& object_pose(int i) const { return rigid_contacts_.pose(i); }
  int selected_object() const { return selected_object_; }
  // The grasper's jaws (null when the tool is not one).
  const TissueGrasp* grasp() const { return grasp_.get(); }
  int grabbed_object() const { return rigid_contacts_.grabbed(); }
  // The dynamic objects after the last Step (a grabbed one's state is where it was let go last).
  const std::vector<DynamicObject>& dynamic_objects() const { return dynamic_objects_; }
  const VisualFrameOptions& options() const { return options_; }

 private:
  // Stage 4's first part: scripted objects placed at the frame's start with their velocity over
  // the frame; the device button (down now, and whether it went down at this frame) applied to
  // grabbing.
  void MoveRigidObjects(bool button_down, bool pressed, const ToolState& tool);
  // The button applied to the grasper's jaws: a press closes them on the points inside, a release
  // opens them.
  void UpdateGrasp(bool button_down, bool pressed, const ToolState& tool, const fem::State& body,
                   VisualFrameStats* stats);
  // Per contact, the velocity the objects' own motion adds to the gap's rate along a direction d,
  // as a vector w with c_object = d·w (zero without a moving object); then c_object per row.
  void CalcObjectVelocities();
  Eigen::VectorXd CalcObjectSeparatingVelocity(const std::vector<Contact>& contacts) const;
  // The dynamic object of rigid object i, or null.
  DynamicObject* FindDynamicObject(int i);
  // Rigid object i is dynamic and not held by the tool (it moves under its own dynamics).
  bool IsFreeDynamicObject(int i) const {
    return i >= 0 && rigid_contacts_.object(i).dynamic && i != grabbed_object();
  }
  // End of stage 5: dynamic objects stepped with the solve's impulses; objects at their
  // end-of-frame poses; the touched grabbable object selected.
  void FinishRigidObjects(const ToolState& tool);
  // Velocity of object i's material point at p_W_m, world (the tool's motion for a grabbed one).
  Eigen::Vector3d CalcObjectPointVelocity(int i, const Eigen::Vector3d& p_W_m,
                                          const ToolState& tool) const;
  void DetectContacts(const fem::State& body, const ToolState& tool);
  // CalcContactJacobian over the body's dofs (none without a body).
  ContactJacobian CalcJacobian(const std::vector<Contact>& contacts,
                               const Eigen::Vector3d& x_tool_W_m) const;
  // Sets the response's sub-stage times in `stats`.
  void SolveResponse(const ToolState& tool, const fem::State& body, VisualFrameStats* stats);
  void SetBodyCompliance(int num_rows);  // W_body_, W_body_haptic_ of the frame's rows
  // Friction law: mu_per_contact_ for this frame's contacts_.
  void SetFrictionCoefficients();
  // W λ from λ's nonzero entries alone: of a frame's candidate contacts most carry no force
  // (block_press_friction: ~70 active of ~210, with three rows each).
  static Eigen::VectorXd MultiplyByImpulses(const Eigen::MatrixXd& W,
                                            const Eigen::VectorXd& lambda);
  // A grasp row of a point that slipped out of the jaws at this frame's end: it leaves the model.
  bool IsLetGo(const Contact& contact) const {
    return contact.bilateral && !(grasp_ && grasp_->Holds(contact.nodes[0]));
  }
  void BuildLinearModel(const DeviceState& device, const Eigen::Isometry3d& X_WT_start,
                        const ToolState& tool, const ToolState& haptic_tool,
                        const fem::State& body);
  // J_all: the Jacobian of `moved` at the haptic tool.
  void ExportContactRows(const std::vector<Contact>& moved, const ContactJacobian& J_all,
                         const Eigen::VectorXd& b_all, const Eigen::VectorXd& held_m_s,
                         const ToolState& tool, const fem::State& body);
  // The frame's contacts as seen from the haptic tool at the end of the frame (points, normals
  // and gaps), with the velocity target b each row holds over the next frame.
  void MoveContactsToHapticTool(const Eigen::Isometry3d& X_WT_start, const ToolState& visual_tool,
                                const ToolState& haptic_tool, std::vector<Contact>* moved,
                                Eigen::VectorXd* b) const;
  // Returns the number of nodes (embedded surface points) moved; *max_penetration_m receives the
  // deepest one found.
  // *max_object_penetration_m receives the deepest body node inside a rigid object.
  int RunSanityPass(const ToolState& tool, fem::State* body, double* max_penetration_m,
                    double* max_object_penetration_m);
  // Scratch of RunSanityPass: the pass that last checked each body node against the tool.
  std::vector<int> node_checked_stamp_;
  int sanity_stamp_ = 0;

  // A scripted object's mean velocity over the frame, about its origin at the frame's start.
  struct ObjectMotion {
    Eigen::Vector3d x_W_m = Eigen::Vector3d::Zero();
    Eigen::Vector3d v_W_m_s = Eigen::Vector3d::Zero();
    Eigen::Vector3d w_W_rad_s = Eigen::Vector3d::Zero();
  };

  const fem::Model* body_;  // null: no deformable body
  ToolModel tool_;
  VisualFrameOptions options_;
  int rows_per_contact_;
  bool objects_have_own_friction_;  // friction law and an object with its own μ
  Eigen::VectorXd mu_per_contact_;  // friction law: μ of each contact this frame
  ImpulseWarmStart impulse_start_;  // unilateral and friction laws: last frame's λ by contact
  std::unique_ptr<fem::TimeStepper> stepper_;  // with a body
  std::unique_ptr<fem::WarpedCompliance> warped_compliance_;  // with a body, kWarped only
  // ModelComplianceStep::kHaptic: a stepper at the haptic Δt (never stepped: it only holds the
  // rest system matrix A_u(Δt_h)) and the warped compliance of that matrix.
  std::unique_ptr<fem::TimeStepper> haptic_stepper_;
  std::unique_ptr<fem::WarpedCompliance> haptic_compliance_;
  std::unique_ptr<CollisionDetector> detector_;  // with a body
  RigidObjectContacts rigid_contacts_;
  // Rigid objects' state: motion this frame (zero for a still one), selection and grabbing.
  std::vector<ObjectMotion> object_motion_;
  std::vector<DynamicObject> dynamic_objects_;  // the rigid objects with `dynamic`, in order
  long frame_index_ = 0;
  int selected_object_ = -1;
  bool button_was_down_ = false;
  Eigen::Isometry3d X_TO_grabbed_ = Eigen::Isometry3d::Identity();
  std::vector<int> surface_nodes_;  // the body's free surface nodes (body–object contacts, grasp)
  std::unique_ptr<TissueGrasp> grasp_;        // options.grasp with a body
  std::unique_ptr<BodyBodyContacts> body_contacts_;  // a body of two objects or more
  std::vector<std::uint8_t> bilateral_rows_;  // per row of the frame: a grasp row
  // Frame data, in stage order.
  CouplingWrench wrench_;
  ToolStepSystem tool_system_;
  Eigen::Vector3d dv_tool_, dL_tool_;
  Eigen::VectorXd du_body_;
  // The last frame's contact correction A⁻¹ Δt J_uᵀλ: the post-collision solve's warm start.
  // Between frames du_body_ = free change + du_contact_ (empty after a frame without rows), so
  // du_body_ − du_contact_ is the last free change, the free solve's warm start.
  Eigen::VectorXd du_contact_;
  std::vector<Contact> contacts_;
  ContactJacobian jacobian_;
  // J_u A_u⁻¹ J_uᵀ at the visual step, the frame's solve, plus the dynamic objects' parts: all
  // that yields but the tool. By columns (as readers ask) under the unilateral law with the
  // warped compliance, else whole.
  FrameCompliance W_body_;
  FrameCompliance W_body_haptic_;  // the same at the haptic step (ModelComplianceStep::kHaptic)
  FrameCompliance W_;              // W_body_ and the tool's part: the frame's solve
  Eigen::VectorXd b_, lambda_;
  std::vector<Eigen::Vector3d> object_velocity_;  // w of each contact (CalcObjectVelocities)
  Eigen::VectorXd c_post_;  // separating velocity of each row after the response
  ContactSolveReport last_solve_;
  LinearContactModel linear_model_;
  ContactRows contact_rows_;
};

}  // namespace hapsim::contact
