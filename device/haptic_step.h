#pragma once
// One step of the 1 kHz haptic loop in the `hybrid` (the default), `linear` (the paper's) and
// `lcp` modes (DESIGN.md §1, §4, §5):
//   1 read the device   2 coupling wrench between device and haptic tool
//   3 free tool update: A_v, A_L, F̃, T̃ at the haptic Δt, and F̂ = F̃ + A_v v/Δt, T̂ = T̃ + A_L L/Δt
//   4 contact force and torque on the haptic tool, either
//       linear: from the linear contact model, F_c = F_c0 + ∂F_c/∂F̂ F̂ + ∂F_c/∂T̂ T̂ (and T_c), or
//       lcp:    from the unilateral solve on the frame's contact rows (HapticLcpSolver), which
//               lets contacts separate and re-engage between visual frames; with the friction
//               law, Coulomb friction on them too (HapticFrictionSolver), or
//       hybrid: from the same solve with the frame's active rows held as equalities (as the
//               linear model holds them) and its other rows unilateral, each of those with the
//               gap it has now that the haptic tool has moved (CalcFreeRowTargets)
//   5 post-contact state: A_v Δv = Δt (F̃ + F_c), A_L ΔL = Δt (T̃ + T_c), advance
//   6 output: the coupling's reaction −F, −T to the device.
// The linear step is fixed-size and allocates nothing; the lcp step allocates nothing after
// construction (up to the solver's max_rows; both checked in tests).

#include <Eigen/Core>

#include "contact/haptic_lcp_solver.h"
#include "contact/linear_contact_model.h"
#include "core/rigid_tool.h"
#include "core/tool_integrator.h"
#include "core/virtual_coupling.h"
#include "device/geometric_haptic_contact.h"

namespace hapsim::device {

struct HapticOutput {
  Eigen::Vector3d device_force_W_N = Eigen::Vector3d::Zero();      // sent to the device: −F
  Eigen::Vector3d device_torque_W_N_m = Eigen::Vector3d::Zero();   // sent to the device: −T
  Eigen::Vector3d contact_force_W_N = Eigen::Vector3d::Zero();     // F_c on the haptic tool
  Eigen::Vector3d contact_torque_W_N_m = Eigen::Vector3d::Zero();  // T_c on the haptic tool
  // lcp: the solve failed (too many rows, singular W) and the linear model was used instead.
  bool lcp_fell_back = false;
};

// The work a 1 kHz step may spend on the rows' solve (lcp and hybrid modes): equality solves on
// an active set (HapticLcpSolver's max_solves_per_step). At ~260 rows one costs ~14 µs on the AMD
// EPYC VM, so a step at the budget took 0.56–0.63 ms in trainer sessions, within the period; a
// solve that needs more goes on over the next steps. In a session's log (10,935 steps, replayed)
// 4 consecutive steps reached it: a new frame's 259 rows of which 116 ended active, where the
// unbounded solve had taken 127 solves and 1.8 ms in one step (issue 25 item 4).
constexpr int kLcpSolvesPerStep = 32;

class HapticStep {
 public:
  // lcp_max_rows: capacity of the rows' solver (0: no rows; memory ≈ 16 lcp_max_rows² bytes);
  // lcp_friction_sweeps > 0: it also solves friction rows, with that many sweeps a step;
  // hold_frame_contacts: it holds the frame's active rows as equalities (the hybrid mode).
  HapticStep(ToolModel tool, const CouplingParams& coupling, const Eigen::Vector3d& gravity_m_s2,
             double dt_s, const ToolState& initial_tool, int lcp_max_rows = 0,
             int lcp_friction_sweeps = 0, bool hold_frame_contacts = false);

  // Replaces the contact model (a copy of fixed-size data: no allocation).
  void SetContactModel(const contact::LinearContactModel& model) { model_ = model; }
  // lcp and hybrid modes: the rows to solve on from the next step (not copied: they must stay
  // unchanged until replaced); nullptr returns to the linear model. The model set by
  // SetContactModel is the fallback when a solve fails. `prepared`, if given, is a solver on
  // which Prepare(rows) was called off the loop (it is then used, and must outlive its use); else
  // the step's own. `linearised`: the tool state the rows were linearised at (their gaps are
  // for it); null: the haptic tool as it stands (the in-process simulator's frame).
  void SetContactRows(const contact::ContactRows* rows,
                      contact::HapticLcpSolver* prepared = nullptr,
                      const ToolState* linearised = nullptr);
  // Prepares the step's own solver for `rows` (HapticLcpSolver::Prepare with the tool system at
  // the current haptic tool state), so that the first step on them is a warm one: for the
  // in-process simulator, which calls it at the visual frame. Returns Prepare's result.
  bool PrepareContactRows(const contact::ContactRows& rows);
  // Penalty, material and impact modes: the contact force comes from `geometric` (not owned;
  // it must outlive its use) in place of the linear model and rows; nullptr: back to them.
  void SetGeometricContact(GeometricHapticContact* geometric) { geometric_ = geometric; }
  int lcp_max_rows() const { return lcp_.max_rows(); }
  // The rows the last steps solved (0: none, the linear model) and the solver that solved them
  // (its last_* counters describe the last Step): for the loop's account of its slowest steps.
  int num_rows_in_use() const { return rows_ != nullptr ? static_cast<int>(rows_->num_rows()) : 0; }
  const contact::HapticLcpSolver& rows_solver() const { return *solver_; }
  HapticOutput Step(const DeviceState& device);

  const ToolState& tool_state() const { return tool_state_; }
  // The haptic tool as a coupling target for the visual tool (pose and velocities).
  DeviceState tool_as_target() const;
  double dt_s() const { return dt_s_; }
  const Eigen::Vector3d& gravity_m_s2() const { return gravity_m_s2_; }
  const ToolModel& tool_model() const { return tool_; }
  const CouplingParams& coupling() const { return coupling_; }

 private:
  ToolModel tool_;
  CouplingParams coupling_;
  Eigen::Vector3d gravity_m_s2_;
  double dt_s_;
  ToolState tool_state_;
  contact::LinearContactModel model_;  // no contact until the first SetContactModel
  const contact::ContactRows* rows_ = nullptr;
  contact::HapticLcpSolver lcp_;
  contact::HapticLcpSolver* solver_ = &lcp_;
  GeometricHapticContact* geometric_ = nullptr;
  // hybrid: the free rows' targets of this step (CalcFreeRowTargets), the tool state the rows
  // are linearised at and the steps taken on them.
  Eigen::VectorXd targets_;
  ToolState rows_linearised_at_;
  long steps_on_rows_ = 0;

  bool TracksFreeRows() const;
  void CalcFreeRowTargets();
};

// A device state at the tool's pose and velocities (a coupling target with zero error).
DeviceState MakeDeviceAtTool(const ToolModel& tool, const ToolState& state);

// The tool's step system at `state` with the coupling's Jacobians at zero coupling error: the
// system HapticLcpSolver::Prepare is given (any state near the haptic tool's will do).
ToolStepSystem CalcLinearisationSystem(const ToolModel& tool, const CouplingParams& coupling,
                                       const Eigen::Vector3d& gravity_m_s2, double dt_s,
                                       const ToolState& state);

}  // namespace hapsim::device
