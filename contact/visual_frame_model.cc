// Stages 6 and 7 of the visual frame: the linear contact model handed to the haptic step, and
// the sanity pass.
#include <Eigen/Dense>
#include <algorithm>
#include <limits>

#include "contact/visual_frame.h"

namespace hapsim::contact {

// Contact points ride with the visual tool over the frame, then over to the haptic tool (the
// identity when the model is linearised at the visual tool). Moving a tool point p by δp changes
// the gap by −n·δp, so the gaps follow the same motion. Targets are velocities the model holds
// for a whole visual frame (until the next model): close a gap over that frame, or undo a
// fraction β of a penetration over it. A one-haptic-step target (−φ/Δt_haptic) would drive the
// tool through the body over the 33 steps it is held.
void VisualFrame::MoveContactsToHapticTool(const Eigen::Isometry3d& X_WT_start,
                                           const ToolState& visual_tool,
                                           const ToolState& haptic_tool,
                                           std::vector<Contact>* moved, Eigen::VectorXd* b) const {
  const Eigen::Isometry3d motion = CalcPose(haptic_tool) * X_WT_start.inverse();
  const Eigen::Isometry3d visual_motion = CalcPose(visual_tool) * X_WT_start.inverse();
  moved->assign(contacts_.begin(), contacts_.end());
  b->setZero(rows_per_contact_ * static_cast<int>(contacts_.size()));
  for (size_t i = 0; i < moved->size(); ++i) {
    const int row = rows_per_contact_ * static_cast<int>(i);
    Contact& contact = (*moved)[i];
    contact.gap_m += options_.dt_s * c_post_[row];  // gap at the end of the frame, to first order
    if (contact.on_tool) {
      const Eigen::Vector3d p_visual_W_m = visual_motion * contact.p_tool_W_m;
      contact.p_tool_W_m = motion * contact.p_tool_W_m;
      contact.n_W = motion.linear() * contact.n_W;
      contact.gap_m -= contact.n_W.dot(contact.p_tool_W_m - p_visual_W_m);  // haptic tool's offset
    }  // a body node on a rigid object: neither moves with the tool
    const double fraction =
        contact.gap_m >= 0.0 && !contact.bilateral ? 1.0 : options_.response.stabilization_beta;
    (*b)[row] = -fraction * contact.gap_m / options_.dt_s;
  }
  // A moving object is taken to keep its velocity over the next frame: the rows hold
  // J v + c_object ≥ b, i.e. J v ≥ b − c_object, along the moved contacts' own directions.
  *b -= CalcObjectSeparatingVelocity(*moved);
}

// The model is linearised at the post-collision state, for the haptic step: the tool matrices
// use the haptic Δt and the coupling at the new tool pose; the body's compliance is the one of
// the visual step (the paper's choice) or, with ModelComplianceStep::kHaptic, of the haptic step
// (DESIGN.md §4's open question; docs/RESULTS.md measures both). Only active constraints (λ > 0)
// enter, and the grasp's rows (any λ: they are equalities): an inactive unilateral contact would
// otherwise act as an equality and pull the tool. The lcp rows take every contact: the 1 kHz
// solve decides which are active.
void VisualFrame::BuildLinearModel(const DeviceState& device, const Eigen::Isometry3d& X_WT_start,
                                   const ToolState& visual_tool, const ToolState& tool,
                                   const fem::State& body) {
  std::vector<Contact> moved;
  Eigen::VectorXd b_all;
  MoveContactsToHapticTool(X_WT_start, visual_tool, tool, &moved, &b_all);
  std::vector<int> active_rows;
  for (size_t i = 0; i < moved.size(); ++i) {
    const int row = rows_per_contact_ * static_cast<int>(i);
    if (IsLetGo(moved[i]) || (!(lambda_[row] > 0.0) && !moved[i].bilateral)) continue;
    for (int d = 0; d < rows_per_contact_; ++d) active_rows.push_back(row + d);
  }
  // With the lcp rows to export, every moved contact's rows once, the model's and the rows' a
  // selection of them; else the model's alone (the linear mode, on block_press_large's ~440
  // contacts, paid 0.05 ms for the others').
  ContactJacobian J_all, J;
  if (options_.export_contact_rows) {
    J_all = CalcJacobian(moved, tool.x_W_m);
    J = SelectRows(J_all, active_rows);
  } else {
    std::vector<Contact> active;
    for (size_t r = 0; r < active_rows.size(); r += static_cast<size_t>(rows_per_contact_))
      active.push_back(moved[static_cast<size_t>(active_rows[r] / rows_per_contact_)]);
    J = CalcJacobian(active, tool.x_W_m);
  }
  const CouplingWrench wrench =
      CalcCouplingWrench(options_.coupling, device, tool, CalcAngularVelocity(tool_, tool));
  const ToolStepSystem haptic =
      CalcToolStepSystem(tool_, tool, wrench, options_.gravity_m_s2, options_.haptic_dt_s);
  // The columns read below: the active rows' and those of every row with λ ≠ 0 (a let-go grasp
  // row keeps its λ).
  FrameCompliance& W_body_part = haptic_compliance_ ? W_body_haptic_ : W_body_;
  std::vector<Eigen::Index> loaded(active_rows.begin(), active_rows.end());
  for (Eigen::Index row = 0; row < lambda_.size(); ++row)
    if (lambda_[row] != 0.0) loaded.push_back(row);
  W_body_part.Fill(loaded);
  const Eigen::MatrixXd& W_body = W_body_part.W();
  Eigen::MatrixXd W = CalcToolDelassus(J, haptic);
  Eigen::VectorXd b(active_rows.size());
  for (size_t c = 0; c < active_rows.size(); ++c) {  // down W's and W_body's columns
    b[c] = b_all[active_rows[c]];
    for (size_t r = 0; r < active_rows.size(); ++r)
      W(r, c) += W_body(active_rows[r], active_rows[c]);
  }
  // The equality law's compliance, as the frame's solve holds it.
  if (options_.response.solve.law == ContactLaw::kEquality)
    AddEqualityCompliance(options_.response.solve.equality_compliance, &W);
  // The body's velocity without contact over a haptic step: its post-frame velocity less what the
  // frame's contact force λ_vis holds back, u̇ − Δt_h A_u⁻¹ J_uᵀ λ_vis, so that J_u u̇_free =
  // J_u u̇ − Δt_h W_body λ_vis. A body resting under the tool (u̇ = 0) then yields only to a
  // change of force from λ_vis, not to the whole force each millisecond.
  const Eigen::VectorXd held_m_s = options_.haptic_dt_s * MultiplyByImpulses(W_body, lambda_);
  Eigen::VectorXd body_rhs = b - J.J_u * body.v_m_s;
  for (size_t r = 0; r < active_rows.size(); ++r) body_rhs[r] += held_m_s[active_rows[r]];
  linear_model_ = MakeLinearContactModel(J, W, haptic, body_rhs);
  if (options_.export_contact_rows) ExportContactRows(moved, J_all, b_all, held_m_s, tool, body);
}

// The rows that travel to the lcp step (issue 13 item 5). Every candidate contact travels, for a
// tool may cross the whole detection margin within one frame (a 0.5 m/s press covers 15 mm of a
// 30 ms frame) and must meet a row there. What is cut is the coupling, W_body's O(n²) entries:
// only the contacts the frame found active, and those the tool could engage within the frame at
// its approach now plus up to lcp_reach_m_s more, keep their coupling to one another. Every
// other contact keeps only its own block of W_body, as if pushing it moved no other contact: a
// stiffer body, for the rest of a frame the tool was not expected to reach it in, and then the
// next frame couples it. A coupled row's target is r_i = b_i − J_u,i u̇ + Δt_h (W_body λ_vis)_i
// (b closes its gap over a frame, less the body's own normal velocity, plus what the frame's force
// holds back, which the 1 kHz solve's W_body λ adds back while λ stays near λ_vis). So while the
// other contacts push as the frame had them push, row i engages once the tool's separating
// velocity J_v,i v + J_ω,i ω falls to b_i − J_u,i u̇: how far it must still fall is its shortfall.
// (With the hold-back counted as well, as if every other contact let go, the hybrid mode, whose
// haptic-step compliance makes the hold-back large, coupled ~175 of block_press's ~213 contacts
// instead of 74, for the same device force to 2e-15 N RMS; docs/BENCHMARKS.md, eighth pass.) An
// uncoupled row sees no other contact's λ, so its target leaves the hold-back out too: the
// frame's force at the other contacts stays in u̇, as if they kept pushing as they did (its own
// λ_vis is 0: an active contact is coupled). The grasp's rows come first
// (ContactRows::num_bilateral_rows), then the coupled contacts, then the others, the nearest to
// engaging first, as many as lcp_max_rows leaves room for. lcp_reach_m_s = 0 couples them all.
void VisualFrame::ExportContactRows(const std::vector<Contact>& moved, const ContactJacobian& J_all,
                                    const Eigen::VectorXd& b_all, const Eigen::VectorXd& held_m_s,
                                    const ToolState& tool, const fem::State& body) {
  const Eigen::VectorXd rhs_uncoupled = b_all - J_all.J_u * body.v_m_s;
  const Eigen::VectorXd rhs_all = rhs_uncoupled + held_m_s;
  const double reach_m_s = options_.lcp_reach_m_s;
  const Eigen::Vector3d w_W_rad_s = CalcAngularVelocity(tool_, tool);
  std::vector<size_t> bilateral, coupled, uncoupled;  // contacts
  std::vector<double> shortfall_m_s(moved.size());    // approach beyond the present one to engage
  for (size_t i = 0; i < moved.size(); ++i) {
    if (moved[i].bilateral) {
      if (!IsLetGo(moved[i])) bilateral.push_back(i);
      continue;
    }
    const int normal = rows_per_contact_ * static_cast<int>(i);
    const double tool_separating_m_s =
        J_all.J_v.row(normal).dot(tool.v_W_m_s) + J_all.J_w.row(normal).dot(w_W_rad_s);
    shortfall_m_s[i] = tool_separating_m_s - rhs_uncoupled[normal];
    const bool reachable =
        reach_m_s == 0.0 || lambda_[normal] > 0.0 || shortfall_m_s[i] < reach_m_s;
    (reachable ? coupled : uncoupled).push_back(i);
  }
  std::stable_sort(uncoupled.begin(), uncoupled.end(),
                   [&](size_t a, size_t b) { return shortfall_m_s[a] < shortfall_m_s[b]; });
  if (options_.lcp_max_rows > 0) {
    const size_t room = static_cast<size_t>(options_.lcp_max_rows / rows_per_contact_);
    const size_t taken = bilateral.size() + coupled.size();
    uncoupled.resize(std::min(uncoupled.size(), room - std::min(room, taken)));
  }
  std::vector<int> rows;
  std::vector<double> mu;
  for (const std::vector<size_t>* group : {&bilateral, &coupled, &uncoupled}) {
    for (size_t i : *group) {
      for (int d = 0; d < rows_per_contact_; ++d)
        rows.push_back(rows_per_contact_ * static_cast<int>(i) + d);
      if (rows_per_contact_ == 3) mu.push_back(mu_per_contact_[static_cast<Eigen::Index>(i)]);
    }
  }
  const ContactJacobian J = SelectRows(J_all, rows);
  // What the hybrid mode follows the rows with (ContactRows::gap_m): b_all = b_gap − c_object.
  const Eigen::VectorXd c_object = CalcObjectSeparatingVelocity(moved);
  const Eigen::VectorXd body_normal_velocity = b_all - rhs_uncoupled;  // J_u u̇
  Eigen::VectorXd rhs(static_cast<Eigen::Index>(rows.size()));
  Eigen::VectorXd lambda(rhs.size()), gap_target(rhs.size()), surface_velocity(rhs.size());
  Eigen::VectorXd gap_m = Eigen::VectorXd::Zero(rhs.size());
  const int num_coupled =
      rows_per_contact_ * static_cast<int>(bilateral.size() + coupled.size());  // rows
  for (size_t r = 0; r < rows.size(); ++r) {
    rhs[static_cast<Eigen::Index>(r)] =
        static_cast<int>(r) < num_coupled ? rhs_all[rows[r]] : rhs_uncoupled[rows[r]];
    lambda[static_cast<Eigen::Index>(r)] = lambda_[rows[r]];
    gap_target[static_cast<Eigen::Index>(r)] = b_all[rows[r]] + c_object[rows[r]];
    surface_velocity[static_cast<Eigen::Index>(r)] =
        body_normal_velocity[rows[r]] + c_object[rows[r]];
    if (rows[r] % rows_per_contact_ == 0)
      gap_m[static_cast<Eigen::Index>(r)] = moved[rows[r] / rows_per_contact_].gap_m;
  }
  const Eigen::VectorXd mu_ordered =
      Eigen::Map<const Eigen::VectorXd>(mu.data(), static_cast<Eigen::Index>(mu.size()));
  // An uncoupled contact keeps its own block of W_body alone (zeros elsewhere, for dense readers):
  // the coupled rows' columns and the others' own entries are all MakeContactRows reads (by
  // columns, FrameCompliance, the rows are normal rows: a row's own block is its diagonal entry).
  FrameCompliance& W_body = haptic_compliance_ ? W_body_haptic_ : W_body_;
  W_body.Fill(std::vector<Eigen::Index>(rows.begin(), rows.begin() + num_coupled));
  W_body.WriteDiagonalOfUnformedColumns();
  contact_rows_ = MakeContactRows(J, W_body.W(), rows, rhs, mu_ordered, num_coupled);
  contact_rows_.lambda_frame_N = lambda;
  contact_rows_.gap_m = gap_m;
  contact_rows_.gap_target_m_s = gap_target;
  contact_rows_.surface_velocity_m_s = surface_velocity;
  contact_rows_.num_bilateral_rows = rows_per_contact_ * static_cast<int>(bilateral.size());
  StampNewContactRows(&contact_rows_);  // last: the rows are complete
}

namespace {

// The surface a body point p_W must not pass: its signed distance (< 0 inside), its closest
// point, its outward normal there, and that surface's velocity at p_W.
struct SanitySurface {
  double distance_m;
  Eigen::Vector3d closest_W_m, n_W, v_W_m_s;
};

// A point of an embedded collision surface, p = Σ w_k x_k (its nodes lie inside the body), moved
// out of the surface `surface_of(p)` gives it when deeper than tolerance_m, by the least change
// of its free nodes: Δx_k = w_k δ / Σ_free w_j² moves p by exactly δ; its closing velocity is
// removed the same way. Returns whether it moved.
template <typename SurfaceOf>
bool MoveEmbeddedPointOut(const Contact& contact, const std::vector<std::uint8_t>& dof_is_fixed,
                          double tolerance_m, const SurfaceOf& surface_of, fem::State* body) {
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero(), v_W = Eigen::Vector3d::Zero();
  double free_weight_sq = 0.0;
  for (int k = 0; k < kMaxContactNodes && contact.nodes[k] >= 0; ++k) {
    const int node = contact.nodes[k];
    p_W += contact.weights[k] * body->x_m.segment<3>(3 * node);
    v_W += contact.weights[k] * body->v_m_s.segment<3>(3 * node);
    if (!dof_is_fixed[3 * node]) free_weight_sq += contact.weights[k] * contact.weights[k];
  }
  const SanitySurface s = surface_of(contact, p_W);
  if (s.distance_m >= -tolerance_m || !(free_weight_sq > 0.0)) return false;
  const Eigen::Vector3d dx_W = s.closest_W_m - p_W;
  const double closing = (v_W - s.v_W_m_s).dot(s.n_W);
  const Eigen::Vector3d dv_W =
      closing < 0.0 ? Eigen::Vector3d(-closing * s.n_W) : Eigen::Vector3d::Zero();
  for (int k = 0; k < kMaxContactNodes && contact.nodes[k] >= 0; ++k) {
    const int node = contact.nodes[k];
    if (dof_is_fixed[3 * node]) continue;
    const double share = contact.weights[k] / free_weight_sq;
    body->x_m.segment<3>(3 * node) += share * dx_W;
    body->v_m_s.segment<3>(3 * node) += share * dv_W;
  }
  return true;
}

}  // namespace

int VisualFrame::RunSanityPass(const ToolState& tool, fem::State* body, double* max_penetration_m,
                               double* max_object_penetration_m) {
  *max_penetration_m = 0.0;
  *max_object_penetration_m = 0.0;
  if (body_ == nullptr) return 0;
  const Eigen::Isometry3d X_WT = CalcPose(tool);
  const Eigen::Isometry3d X_TW = X_WT.inverse();
  const Eigen::Vector3d w_W = CalcAngularVelocity(tool_, tool);
  // The tool's surface, or the rigid object's (moving: its velocity; fixed: zero).
  const auto surface_of = [&](const Contact& contact, const Eigen::Vector3d& p_W) {
    if (contact.rigid_object < 0) {
      const ToolDistance d = detector_->tool_distance().Calc(X_TW * p_W);
      *max_penetration_m = std::max(*max_penetration_m, -d.distance_m);
      return SanitySurface{d.distance_m, X_WT * d.closest_T_m, X_WT.linear() * d.normal_T,
                           tool.v_W_m_s + w_W.cross(p_W - tool.x_W_m)};
    }
    const RigidObjectContacts::Penetration d = rigid_contacts_.CalcDeepest(p_W);
    *max_object_penetration_m = std::max(*max_object_penetration_m, -d.distance_m);
    // A node inside a dynamic object is left to the stabilisation: moving the node alone onto a
    // surface that moves with the contact's reaction made energy (a cube resting on a soft block
    // jittered at 2 mm/s; left alone it settles to 1e-5 mm/s: ObjectDynamics.CubeOnASoftBlock...).
    if (IsFreeDynamicObject(d.object))
      return SanitySurface{std::numeric_limits<double>::infinity(), p_W, d.normal_W,
                           Eigen::Vector3d::Zero()};
    return SanitySurface{d.distance_m, d.closest_W_m, d.normal_W,
                         CalcObjectPointVelocity(d.object, p_W, tool)};
  };
  int corrections = 0;
  node_checked_stamp_.resize(static_cast<size_t>(body_->num_nodes()), 0);
  if (++sanity_stamp_ == std::numeric_limits<int>::max()) {  // wrap: no stale stamp may match
    std::fill(node_checked_stamp_.begin(), node_checked_stamp_.end(), 0);
    sanity_stamp_ = 1;
  }
  for (const Contact& contact : contacts_) {
    if (contact.bilateral) continue;  // a held point sits where the jaws hold it
    // Two of the body's objects: the stabilisation (β) undoes their overlap; moving a node onto
    // a face that itself moves would need both sides.
    if (KindOf(contact) == ContactKind::kBodyBody) continue;
    if (contact.embedded) {
      corrections += MoveEmbeddedPointOut(contact, body_->dof_is_fixed, options_.sanity_tolerance_m,
                                          surface_of, body);
      continue;
    }
    for (int k = 0; k < kMaxContactNodes && contact.nodes[k] >= 0; ++k) {  // slots [0, k) used
      const int node = contact.nodes[k];
      if (body_->dof_is_fixed[3 * node]) continue;
      // A node in several of the tool's contacts (a node contact, the feature contacts of its
      // faces) is checked once: checked again against the same surface it is found where the
      // first check left it, on it or outside, within sanity_tolerance_m (> 0, far above the
      // projection's round-off). Nothing else moves it between: the tool's contacts come first
      // in contacts_ (DetectContacts), before the objects' that also move nodes.
      if (contact.rigid_object < 0) {
        if (node_checked_stamp_[node] == sanity_stamp_) continue;
        node_checked_stamp_[node] = sanity_stamp_;
      }
      const SanitySurface s = surface_of(contact, body->x_m.segment<3>(3 * node));
      if (s.distance_m >= -options_.sanity_tolerance_m) continue;
      body->x_m.segment<3>(3 * node) = s.closest_W_m;
      // Remove the velocity that would carry the node back inside.
      const double closing = (body->v_m_s.segment<3>(3 * node) - s.v_W_m_s).dot(s.n_W);
      if (closing < 0.0) body->v_m_s.segment<3>(3 * node) -= closing * s.n_W;
      ++corrections;
    }
  }
  return corrections;
}

}  // namespace hapsim::contact
