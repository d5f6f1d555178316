// Fuzz target: a CONTACT_MODEL datagram (contact_model_t) as the haptic process receives it,
// messages::Decode then messages::FromMessage, and what the 1 kHz loop does with a model it
// accepts: the linear model's evaluation and, on the rows, the lcp mode's solve
// (contact::HapticLcpSolver, which promises never to throw or allocate).
//
// An accepted model must hold what adapters.h promises: finite values, dt > 0, sizes that agree
// with num_rows, unit normals in J_v, a symmetric W_body with a diagonal >= 0, lambda >= 0, unit
// quaternions. FromMessage without rows must accept exactly what it accepts with them. The frame's
// world (WorldFromMessage) is finite and made of rotations when accepted.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "contact/haptic_lcp_solver.h"
#include "contact/linear_contact_model.h"
#include "messages/adapters.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/fuzz/message_checks.h"

namespace {

using namespace hapsim;

// Rows the lcp solver holds. The haptic process holds haptic.lcp_max_rows (512 by default), but a
// solver per input keeps inputs independent, and at libFuzzer's input sizes (4 kB) a message
// holds at most ~30 rows; a larger message takes the solver's "too many rows" path.
constexpr int kMaxRows = 64;
// J_v row norms: adapters.cc accepts |‖n‖ − 1| up to this.
constexpr double kUnitTolerance = 1e-6;

void CheckAccepted(const contact::LinearContactModel& model, const contact::ContactRows& rows,
                   const messages::ContactModelHeader& header, int num_rows) {
  using fuzz::CheckOrDie;
  CheckOrDie(std::isfinite(header.dt_visual_s) && header.dt_visual_s > 0.0 &&
                 std::isfinite(header.dt_haptic_s) && header.dt_haptic_s > 0.0,
             "contact_model_t accepted a non-positive or non-finite dt");
  for (const Eigen::Quaterniond& q : {header.q_WT, header.visual_tool.q_WT})
    CheckOrDie(std::abs(q.norm() - 1.0) <= messages::kQuaternionNormTolerance,
               "contact_model_t accepted a quaternion of norm " + std::to_string(q.norm()));
  CheckOrDie(std::isfinite(header.t_frame_s) && header.x_W_m.allFinite() &&
                 header.visual_tool.x_W_m.allFinite() && header.visual_tool.v_W_m_s.allFinite() &&
                 header.visual_tool.L_W_kg_m2_s.allFinite(),
             "contact_model_t accepted a non-finite header");
  CheckOrDie(model.num_contacts >= 0 && model.F_c0_N.allFinite() && model.T_c0_N_m.allFinite() &&
                 model.dFc_dF.allFinite() && model.dFc_dT.allFinite() && model.dTc_dF.allFinite() &&
                 model.dTc_dT.allFinite(),
             "contact_model_t accepted a non-finite linear model or num_contacts < 0");
  const int n = num_rows;
  CheckOrDie(rows.num_rows() == n && rows.J_w.rows() == n && rows.W_body.rows() == n &&
                 rows.W_body.cols() == n && rows.body_rhs.size() == n &&
                 rows.lambda_frame_N.size() == n,
             "contact_model_t rows of sizes that disagree with num_rows " + std::to_string(n));
  CheckOrDie(rows.J_v.allFinite() && rows.J_w.allFinite() && rows.W_body.allFinite() &&
                 rows.body_rhs.allFinite() && rows.lambda_frame_N.allFinite() &&
                 rows.gap_m.allFinite() && rows.gap_target_m_s.allFinite() &&
                 rows.surface_velocity_m_s.allFinite(),
             "contact_model_t accepted non-finite rows");
  CheckOrDie(rows.W_body == rows.W_body.transpose(), "contact_model_t: W_body not symmetric");
  for (int i = 0; i < n; ++i) {
    const bool off_tool = rows.J_v.row(i).norm() == 0.0 && rows.J_w.row(i).norm() == 0.0;
    CheckOrDie(
        std::abs(rows.J_v.row(i).norm() - 1.0) <= kUnitTolerance || off_tool,
        "contact_model_t accepted a J_v row of norm " + std::to_string(rows.J_v.row(i).norm()));
    CheckOrDie(rows.W_body(i, i) >= 0.0 &&
                   (i % rows.rows_per_contact != 0 || rows.lambda_frame_N[i] >= 0.0),
               "contact_model_t accepted a negative W_body diagonal or normal lambda");
  }
  CheckOrDie(contact::HasConsistentShape(rows),
             "contact_model_t accepted rows whose friction or coupling layout is inconsistent");
  // Uncoupled contacts (the last num_uncoupled_rows rows) couple to no other row.
  const int per = rows.rows_per_contact, coupled = rows.num_coupled_rows();
  for (int a = coupled; a < n; a += per)
    CheckOrDie((rows.W_body.block(a, 0, per, a).array() == 0.0).all(),
               "contact_model_t: an uncoupled contact couples to an earlier row");
}

// The frame's world (the geometric modes): whatever the message, WorldFromMessage either
// rejects it with a reason or gives finite positions and unit-rotation poses of the counts the
// message names (expected: the message's own counts, so that the content is what is fuzzed).
void CheckWorld(const hapsim_lcm::contact_model_t& msg) {
  Eigen::VectorXd body_x_m;
  std::vector<Eigen::Isometry3d> poses;
  bool has_world = false;
  std::string error;
  if (!messages::WorldFromMessage(msg, msg.num_body_nodes, msg.num_objects, &body_x_m, &poses,
                                  &has_world, &error)) {
    fuzz::CheckOrDie(!error.empty(), "contact_model_t world rejected without a reason");
    return;
  }
  if (!has_world) return;
  fuzz::CheckOrDie(body_x_m.size() == 3 * msg.num_body_nodes && body_x_m.allFinite() &&
                       static_cast<int>(poses.size()) == msg.num_objects,
                   "contact_model_t accepted a world of the wrong size or non-finite");
  for (const Eigen::Isometry3d& X : poses)
    fuzz::CheckOrDie(
        X.translation().allFinite() &&
            (X.linear().transpose() * X.linear() - Eigen::Matrix3d::Identity()).norm() < 1e-6,
        "contact_model_t accepted a pose that is not a rotation");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hapsim_lcm::contact_model_t msg;
  if (!fuzz::DecodeMessage(data, size, &msg)) return 0;
  CheckWorld(msg);
  contact::LinearContactModel model, model_alone;
  contact::ContactRows rows;
  messages::ContactModelHeader header, header_alone;
  std::string error;
  const bool accepted = messages::FromMessage(msg, &model, &rows, &header, &error);
  const bool accepted_alone =
      messages::FromMessage(msg, &model_alone, nullptr, &header_alone, nullptr);
  fuzz::CheckOrDie(accepted == accepted_alone,
                   "contact_model_t: FromMessage with and without rows disagree");
  if (!accepted) {
    fuzz::CheckOrDie(!error.empty(), "contact_model_t rejected without a reason");
    fuzz::Note(error);
    return 0;
  }
  CheckAccepted(model, rows, header, msg.num_rows);

  // The haptic step on it: a 50 g tool at 1 kHz under a 2000 N/m coupling (A_v = m + dt² k), an
  // inertia of 1e-5 kg m², pressed down with 1 N.
  ToolStepSystem tool;
  tool.dt_s = 1e-3;
  tool.A_v = (0.05 + 1e-6 * 2000.0) * Eigen::Matrix3d::Identity();
  tool.M_inv_W = 1e5 * Eigen::Matrix3d::Identity();
  const Eigen::Vector3d F_hat_N(0.0, 0.0, -1.0), T_hat_N_m(0.0, 1e-3, 0.0);
  Eigen::Vector3d F_c_N, T_c_N_m;
  contact::EvaluateLinearContactModel(model, F_hat_N, T_hat_N_m, &F_c_N, &T_c_N_m);
  // With a friction solve (5 sweeps, the scene default), so that friction rows reach it too.
  contact::HapticLcpSolver solver(kMaxRows, /*friction_sweeps=*/5);
  if (solver.Prepare(rows, tool)) solver.Solve(rows, tool, F_hat_N, T_hat_N_m, &F_c_N, &T_c_N_m);
  return 0;
}
