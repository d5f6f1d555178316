#include "messages/adapters.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

namespace hapsim::messages {
namespace {

void SetError(std::string* error, std::string text) {
  if (error != nullptr) *error = std::move(text);
}

void VectorToArray(const Eigen::Vector3d& v, double out[3]) {
  for (int i = 0; i < 3; ++i) out[i] = v[i];
}

Eigen::Vector3d ArrayToVector(const double in[3]) { return Eigen::Vector3d(in[0], in[1], in[2]); }

void QuaternionToArray(const Eigen::Quaterniond& q, double out[4]) {
  out[0] = q.w();
  out[1] = q.x();
  out[2] = q.y();
  out[3] = q.z();
}

void MatrixToArray(const Eigen::Matrix3d& m, double out[3][3]) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out[r][c] = m(r, c);
  }
}

Eigen::Matrix3d ArrayToMatrix(const double in[3][3]) {
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m(r, c) = in[r][c];
  }
  return m;
}

bool AllFinite(const double* data, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(data[i])) return false;
  }
  return true;
}

// Field names are C strings so that the success path builds no std::string (no allocation).
bool CheckFinite(const double* data, std::size_t n, const char* field, std::string* error) {
  if (AllFinite(data, n)) return true;
  SetError(error, std::string(field) + ": non-finite entry");
  return false;
}

// The quaternion (w, x, y, z) in `in` as a unit quaternion (see adapters.h for the tolerances).
bool ReadUnitQuaternion(const double in[4], const char* field, Eigen::Quaterniond* q,
                        std::string* error) {
  Eigen::Quaterniond q_in(in[0], in[1], in[2], in[3]);
  const double norm = q_in.norm();
  if (!std::isfinite(norm) || std::abs(norm - 1.0) > kQuaternionNormTolerance) {
    SetError(error, std::string(field) + ": quaternion norm " + std::to_string(norm) +
                        " is not within " + std::to_string(kQuaternionNormTolerance) + " of 1");
    return false;
  }
  if (std::abs(norm - 1.0) > kQuaternionRoundOff) q_in.coeffs() /= norm;
  *q = q_in;
  return true;
}

bool CheckSize(std::size_t size, int expected, const char* field, const char* what,
               std::string* error) {
  if (size == static_cast<std::size_t>(expected)) return true;
  SetError(error, std::string(field) + ": " + std::to_string(size) + " " + what + ", expected " +
                      std::to_string(expected) + " (num_rows)");
  return false;
}

// A [num_rows][num_cols] array of the contact model: sizes as declared, entries finite.
bool CheckRowArray(const std::vector<std::vector<double>>& rows, int num_rows, int num_cols,
                   const char* field, std::string* error) {
  if (!CheckSize(rows.size(), num_rows, field, "rows", error)) return false;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (rows[i].size() != static_cast<std::size_t>(num_cols)) {
      SetError(error, std::string(field) + "[" + std::to_string(i) +
                          "]: " + std::to_string(rows[i].size()) + " entries, expected " +
                          std::to_string(num_cols));
      return false;
    }
    if (!AllFinite(rows[i].data(), rows[i].size())) {
      SetError(error, std::string(field) + "[" + std::to_string(i) + "]: non-finite entry");
      return false;
    }
  }
  return true;
}

// A packed lower triangle of an n × n matrix: row i starts at entry PackedRowStart(i), and
// PackedRowStart(n) is the number of entries.
std::int64_t PackedRowStart(std::int64_t i) { return i * (i + 1) / 2; }

// contact_model_t.gap_m, gap_target_m_s, surface_velocity_m_s: none, or one finite entry each
// per row.
bool CheckRowGaps(const hapsim_lcm::contact_model_t& msg, std::string* error) {
  const int gaps = msg.num_row_gaps;
  if (gaps != 0 && gaps != msg.num_rows) {
    SetError(error, "contact_model_t.num_row_gaps: " + std::to_string(gaps) + ", expected 0 or " +
                        std::to_string(msg.num_rows) + " (num_rows)");
    return false;
  }
  return CheckSize(msg.gap_m.size(), gaps, "contact_model_t.gap_m", "entries", error) &&
         CheckFinite(msg.gap_m.data(), gaps, "contact_model_t.gap_m", error) &&
         CheckSize(msg.gap_target_m_s.size(), gaps, "contact_model_t.gap_target_m_s", "entries",
                   error) &&
         CheckFinite(msg.gap_target_m_s.data(), gaps, "contact_model_t.gap_target_m_s", error) &&
         CheckSize(msg.surface_velocity_m_s.size(), gaps, "contact_model_t.surface_velocity_m_s",
                   "entries", error) &&
         CheckFinite(msg.surface_velocity_m_s.data(), gaps, "contact_model_t.surface_velocity_m_s",
                     error);
}

// contact_model_t.rows_per_contact and its friction coefficients: 1 (or 0 without rows) and
// none, or 3 with one finite μ ≥ 0 per three rows.
bool CheckRowLayout(const hapsim_lcm::contact_model_t& msg, std::string* error) {
  const int per = msg.rows_per_contact;
  if (!(per == 1 || per == 3 || (per == 0 && msg.num_rows == 0)) ||
      msg.num_rows % std::max(per, 1) != 0) {
    SetError(error, "contact_model_t.rows_per_contact: " + std::to_string(per) + " with " +
                        std::to_string(msg.num_rows) + " rows (1, or 3 with whole contacts)");
    return false;
  }
  const int expected = per == 3 ? msg.num_rows / 3 : 0;
  if (msg.num_friction_coefficients != expected ||
      msg.friction_coefficient.size() != static_cast<std::size_t>(expected)) {
    SetError(error, "contact_model_t.friction_coefficient: " +
                        std::to_string(msg.num_friction_coefficients) + " declared, " +
                        std::to_string(msg.friction_coefficient.size()) + " entries, expected " +
                        std::to_string(expected) + " (one per contact of 3 rows)");
    return false;
  }
  if (!CheckFinite(msg.friction_coefficient.data(), expected,
                   "contact_model_t.friction_coefficient", error))
    return false;
  for (int i = 0; i < expected; ++i) {
    if (msg.friction_coefficient[i] < 0.0) {
      SetError(error, "contact_model_t.friction_coefficient[" + std::to_string(i) + "]: negative");
      return false;
    }
  }
  return true;
}

// A packed array of contact_model_t: `expected` entries (as `rule` says), declared and present,
// all finite.
bool CheckPackedArray(const std::vector<double>& entries, std::int32_t declared,
                      std::int64_t expected, const char* field, const char* rule,
                      std::string* error) {
  if (declared != expected || entries.size() != static_cast<std::size_t>(expected)) {
    SetError(error, std::string(field) + ": " + std::to_string(declared) + " declared, " +
                        std::to_string(entries.size()) + " entries, expected " +
                        std::to_string(expected) + " (" + rule + ")");
    return false;
  }
  if (!AllFinite(entries.data(), entries.size())) {
    SetError(error, std::string(field) + ": non-finite entry");
    return false;
  }
  return true;
}

// contact_model_t's W_body: num_coupled_rows whole contacts of the num_rows, the packed lower
// triangle of their block, and one packed block per uncoupled contact. After CheckRowLayout.
bool CheckBodyCompliance(const hapsim_lcm::contact_model_t& msg, std::string* error) {
  const int per = std::max<int>(msg.rows_per_contact, 1);
  const int coupled = msg.num_coupled_rows;
  if (coupled < 0 || coupled > msg.num_rows || coupled % per != 0) {
    SetError(error, "contact_model_t.num_coupled_rows: " + std::to_string(coupled) + " of " +
                        std::to_string(msg.num_rows) + " rows, expected whole contacts of " +
                        std::to_string(per));
    return false;
  }
  if (msg.num_bilateral_rows < 0 || msg.num_bilateral_rows > coupled ||
      (msg.num_bilateral_rows > 0 && per != 1)) {
    SetError(error, "contact_model_t.num_bilateral_rows: " +
                        std::to_string(msg.num_bilateral_rows) + ", expected 0 to the " +
                        std::to_string(coupled) + " coupled rows (normal rows only)");
    return false;
  }
  return CheckPackedArray(msg.W_body_lower, msg.num_W_body_lower, PackedRowStart(coupled),
                          "contact_model_t.W_body_lower",
                          "num_coupled_rows (num_coupled_rows + 1) / 2", error) &&
         CheckPackedArray(msg.W_body_contact_lower, msg.num_W_body_contact_lower,
                          (msg.num_rows - coupled) / per * PackedRowStart(per),
                          "contact_model_t.W_body_contact_lower",
                          "one packed rows_per_contact block per uncoupled contact", error);
}

// Where W_body[i][j] (j ≤ i, both in one block) travels in `msg`: its position in W_body_lower
// for coupled rows, else in W_body_contact_lower. Precondition: CheckBodyCompliance, or for
// the encoder the arrays sized. Message: contact_model_t, const or not.
template <typename Message>
auto& PackedBodyEntry(Message& msg, int i, int j) {
  const int coupled = msg.num_coupled_rows;
  if (i < coupled) return msg.W_body_lower[PackedRowStart(i) + j];
  const int per = std::max<int>(msg.rows_per_contact, 1);
  const int contact = (i - coupled) / per, start = coupled + contact * per;
  return msg.W_body_contact_lower[contact * PackedRowStart(per) + PackedRowStart(i - start) +
                                  (j - start)];
}

// Everything FromMessage(contact_model_t) rejects except the quaternion, which it reads itself.
bool CheckContactModel(const hapsim_lcm::contact_model_t& msg, std::string* error) {
  if (!(std::isfinite(msg.dt_visual_s) && msg.dt_visual_s > 0.0)) {
    SetError(error, "contact_model_t.dt_visual_s: must be finite and > 0");
    return false;
  }
  if (!(std::isfinite(msg.dt_haptic_s) && msg.dt_haptic_s > 0.0)) {
    SetError(error, "contact_model_t.dt_haptic_s: must be finite and > 0");
    return false;
  }
  if (msg.num_contacts < 0 || msg.num_rows < 0) {
    SetError(error, msg.num_contacts < 0 ? "contact_model_t.num_contacts: negative"
                                         : "contact_model_t.num_rows: negative");
    return false;
  }
  const int n = msg.num_rows;
  return CheckFinite(&msg.t_frame_s, 1, "contact_model_t.t_frame_s", error) &&
         CheckFinite(msg.x_W_m, 3, "contact_model_t.x_W_m", error) &&
         CheckFinite(msg.visual_x_W_m, 3, "contact_model_t.visual_x_W_m", error) &&
         CheckFinite(msg.visual_v_W_m_s, 3, "contact_model_t.visual_v_W_m_s", error) &&
         CheckFinite(msg.visual_L_W_kg_m2_s, 3, "contact_model_t.visual_L_W_kg_m2_s", error) &&
         CheckFinite(msg.F_c0_N, 3, "contact_model_t.F_c0_N", error) &&
         CheckFinite(msg.T_c0_N_m, 3, "contact_model_t.T_c0_N_m", error) &&
         CheckFinite(&msg.dFc_dF[0][0], 9, "contact_model_t.dFc_dF", error) &&
         CheckFinite(&msg.dFc_dT[0][0], 9, "contact_model_t.dFc_dT", error) &&
         CheckFinite(&msg.dTc_dF[0][0], 9, "contact_model_t.dTc_dF", error) &&
         CheckFinite(&msg.dTc_dT[0][0], 9, "contact_model_t.dTc_dT", error) &&
         CheckRowArray(msg.J_v, n, 3, "contact_model_t.J_v", error) &&
         CheckRowArray(msg.J_w, n, 3, "contact_model_t.J_w", error) &&
         CheckSize(msg.body_rhs.size(), n, "contact_model_t.body_rhs", "entries", error) &&
         CheckFinite(msg.body_rhs.data(), n, "contact_model_t.body_rhs", error) &&
         CheckSize(msg.lambda_frame_N.size(), n, "contact_model_t.lambda_frame_N", "entries",
                   error) &&
         CheckFinite(msg.lambda_frame_N.data(), n, "contact_model_t.lambda_frame_N", error) &&
         CheckRowGaps(msg, error) && CheckRowLayout(msg, error) && CheckBodyCompliance(msg, error);
}

// The ranges of the lcp rows that decoding alone cannot catch: J_v,i = −n_iᵀ is a unit normal, or
// zero with J_ω,i zero for a row that touches no tool (a body node on a rigid object: its row
// couples to the tool's only through the body, CalcContactJacobian);
// W_body is positive semidefinite, so its diagonal is ≥ 0 (symmetry holds by construction: only
// the lower triangle travels); the frame's normal impulses are ≥ 0 but a grasp's (unilateral
// contacts push; a tangential one has either sign).
bool CheckContactRowRanges(const hapsim_lcm::contact_model_t& msg, std::string* error) {
  constexpr double kUnitTolerance = 1e-6;
  for (int i = 0; i < msg.num_rows; ++i) {
    const double norm = std::sqrt(msg.J_v[i][0] * msg.J_v[i][0] + msg.J_v[i][1] * msg.J_v[i][1] +
                                  msg.J_v[i][2] * msg.J_v[i][2]);
    const bool off_tool =
        norm == 0.0 && msg.J_w[i][0] == 0.0 && msg.J_w[i][1] == 0.0 && msg.J_w[i][2] == 0.0;
    if (std::abs(norm - 1.0) > kUnitTolerance && !off_tool) {
      SetError(error, "contact_model_t.J_v[" + std::to_string(i) + "]: norm " +
                          std::to_string(norm) +
                          ", expected a unit normal (or zero, with J_w zero: no tool)");
      return false;
    }
    if (PackedBodyEntry(msg, i, i) < 0.0) {
      SetError(error,
               std::string(i < msg.num_coupled_rows ? "contact_model_t.W_body_lower"
                                                    : "contact_model_t.W_body_contact_lower") +
                   ": negative diagonal entry in row " + std::to_string(i) +
                   " (W_body must be positive semidefinite)");
      return false;
    }
    if (i % std::max<int>(msg.rows_per_contact, 1) == 0 && i >= msg.num_bilateral_rows &&
        msg.lambda_frame_N[i] < 0.0) {
      SetError(error, "contact_model_t.lambda_frame_N[" + std::to_string(i) + "]: negative");
      return false;
    }
  }
  return true;
}

}  // namespace

hapsim_lcm::device_state_t ToMessage(const DeviceState& device, std::int64_t utime,
                                     std::int64_t sequence) {
  hapsim_lcm::device_state_t msg;
  msg.utime = utime;
  msg.sequence = sequence;
  VectorToArray(device.x_W_m, msg.x_W_m);
  QuaternionToArray(device.q_WD, msg.q_WD);
  VectorToArray(device.v_W_m_s, msg.v_W_m_s);
  VectorToArray(device.w_W_rad_s, msg.w_W_rad_s);
  msg.buttons = device.buttons;
  return msg;
}

bool FromMessage(const hapsim_lcm::device_state_t& msg, DeviceState* device, std::string* error) {
  Eigen::Quaterniond q_WD(msg.q_WD[0], msg.q_WD[1], msg.q_WD[2], msg.q_WD[3]);
  // A non-finite quaternion passes through for the safety layer; a finite one must be unit.
  if (AllFinite(msg.q_WD, 4) &&
      !ReadUnitQuaternion(msg.q_WD, "device_state_t.q_WD", &q_WD, error)) {
    return false;
  }
  device->x_W_m = ArrayToVector(msg.x_W_m);
  device->q_WD = q_WD;
  device->v_W_m_s = ArrayToVector(msg.v_W_m_s);
  device->w_W_rad_s = ArrayToVector(msg.w_W_rad_s);
  device->buttons = msg.buttons;
  return true;
}

hapsim_lcm::device_force_t ToMessage(const Eigen::Vector3d& force_W_N,
                                     const Eigen::Vector3d& torque_W_N_m, std::int64_t utime,
                                     std::int64_t sequence, const std::string& zero_reason) {
  hapsim_lcm::device_force_t msg;
  msg.utime = utime;
  msg.sequence = sequence;
  msg.zeroed = zero_reason.empty() ? 0 : 1;
  msg.reason = zero_reason;
  VectorToArray(msg.zeroed ? Eigen::Vector3d::Zero().eval() : force_W_N, msg.force_W_N);
  VectorToArray(msg.zeroed ? Eigen::Vector3d::Zero().eval() : torque_W_N_m, msg.torque_W_N_m);
  return msg;
}

bool FromMessage(const hapsim_lcm::device_force_t& msg, Eigen::Vector3d* force_W_N,
                 Eigen::Vector3d* torque_W_N_m, std::string* error) {
  if (!CheckFinite(msg.force_W_N, 3, "device_force_t.force_W_N", error) ||
      !CheckFinite(msg.torque_W_N_m, 3, "device_force_t.torque_W_N_m", error)) {
    return false;
  }
  *force_W_N = ArrayToVector(msg.force_W_N);
  *torque_W_N_m = ArrayToVector(msg.torque_W_N_m);
  return true;
}

void PoseToMessage(const ToolState& tool, double x_W_m[3], double q_WT[4]) {
  VectorToArray(tool.x_W_m, x_W_m);
  QuaternionToArray(tool.q_WT, q_WT);
}

bool PoseFromMessage(const double x_W_m[3], const double q_WT[4], ToolState* tool,
                     std::string* error) {
  Eigen::Quaterniond q;
  if (!CheckFinite(x_W_m, 3, "x_W_m", error) || !ReadUnitQuaternion(q_WT, "q_WT", &q, error)) {
    return false;
  }
  tool->x_W_m = ArrayToVector(x_W_m);
  tool->q_WT = q;
  return true;
}

bool HapticToolFromMessage(const hapsim_lcm::haptic_state_t& msg, ToolState* tool,
                           std::string* error) {
  ToolState read;
  if (!PoseFromMessage(msg.x_W_m, msg.q_WT, &read, error) ||
      !CheckFinite(msg.v_W_m_s, 3, "haptic_state_t.v_W_m_s", error) ||
      !CheckFinite(msg.L_W_kg_m2_s, 3, "haptic_state_t.L_W_kg_m2_s", error)) {
    return false;
  }
  read.v_W_m_s = ArrayToVector(msg.v_W_m_s);
  read.L_W_kg_m2_s = ArrayToVector(msg.L_W_kg_m2_s);
  *tool = read;
  return true;
}

namespace {

// The rows of a contact model (n = rows.num_rows() > 0) into `msg`: checked, W_body's lower
// triangles packed. Throws std::invalid_argument as ToMessage says.
void RowsToMessage(const contact::ContactRows& rows, hapsim_lcm::contact_model_t* msg) {
  const int n = rows.num_rows();
  if (!contact::HasConsistentShape(rows)) {
    throw std::invalid_argument("messages::ToMessage: ContactRows sizes disagree with J_v's " +
                                std::to_string(n) + " rows or its friction layout");
  }
  // Only lower triangles travel, and of an uncoupled contact only its own block: an asymmetric
  // W_body, or one not zero where the rows say it is, would arrive changed.
  if (rows.W_body != rows.W_body.transpose())
    throw std::invalid_argument("messages::ToMessage: ContactRows.W_body is not symmetric");
  const int per = rows.rows_per_contact;
  const int coupled = rows.num_coupled_rows();
  for (int a = coupled; a < n; a += per) {
    if (!(rows.W_body.block(a, 0, per, a).array() == 0.0).all())
      throw std::invalid_argument("messages::ToMessage: ContactRows.W_body couples uncoupled row " +
                                  std::to_string(a));
  }
  msg->J_v.assign(n, std::vector<double>(3));
  msg->J_w.assign(n, std::vector<double>(3));
  msg->num_coupled_rows = coupled;
  msg->num_bilateral_rows = rows.num_bilateral_rows;
  msg->num_W_body_lower = static_cast<std::int32_t>(PackedRowStart(coupled));
  msg->W_body_lower.resize(msg->num_W_body_lower);
  msg->num_W_body_contact_lower =
      static_cast<std::int32_t>((n - coupled) / per * PackedRowStart(per));
  msg->W_body_contact_lower.resize(msg->num_W_body_contact_lower);
  msg->rows_per_contact = static_cast<std::int8_t>(per);
  msg->body_rhs.resize(n);
  msg->lambda_frame_N.assign(n, 0.0);
  const bool gaps = rows.gap_m.size() == n && rows.gap_target_m_s.size() == n &&
                    rows.surface_velocity_m_s.size() == n;
  msg->num_row_gaps = gaps ? n : 0;
  msg->gap_m.assign(msg->num_row_gaps, 0.0);
  msg->gap_target_m_s.assign(msg->num_row_gaps, 0.0);
  msg->surface_velocity_m_s.assign(msg->num_row_gaps, 0.0);
  for (int i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      msg->J_v[i][c] = rows.J_v(i, c);
      msg->J_w[i][c] = rows.J_w(i, c);
    }
    const int first = contact::FirstRowOfBlock(i, coupled, per);
    for (int c = first; c <= i; ++c) PackedBodyEntry(*msg, i, c) = rows.W_body(i, c);
    msg->body_rhs[i] = rows.body_rhs[i];
    if (rows.lambda_frame_N.size() == n) msg->lambda_frame_N[i] = rows.lambda_frame_N[i];
    if (gaps) {
      msg->gap_m[i] = rows.gap_m[i];
      msg->gap_target_m_s[i] = rows.gap_target_m_s[i];
      msg->surface_velocity_m_s[i] = rows.surface_velocity_m_s[i];
    }
  }
  msg->num_friction_coefficients = static_cast<std::int32_t>(rows.friction_coefficient.size());
  msg->friction_coefficient.assign(
      rows.friction_coefficient.data(),
      rows.friction_coefficient.data() + rows.friction_coefficient.size());
}

}  // namespace

hapsim_lcm::contact_model_t ToMessage(const contact::LinearContactModel& model,
                                      const contact::ContactRows* rows_or_null,
                                      const ContactModelHeader& header) {
  hapsim_lcm::contact_model_t msg{};
  msg.utime = header.utime;
  msg.sequence = header.sequence;
  msg.dt_visual_s = header.dt_visual_s;
  msg.dt_haptic_s = header.dt_haptic_s;
  msg.t_frame_s = header.t_frame_s;
  VectorToArray(header.x_W_m, msg.x_W_m);
  QuaternionToArray(header.q_WT, msg.q_WT);
  VectorToArray(header.visual_tool.x_W_m, msg.visual_x_W_m);
  QuaternionToArray(header.visual_tool.q_WT, msg.visual_q_WT);
  VectorToArray(header.visual_tool.v_W_m_s, msg.visual_v_W_m_s);
  VectorToArray(header.visual_tool.L_W_kg_m2_s, msg.visual_L_W_kg_m2_s);
  msg.num_contacts = model.num_contacts;
  VectorToArray(model.F_c0_N, msg.F_c0_N);
  VectorToArray(model.T_c0_N_m, msg.T_c0_N_m);
  MatrixToArray(model.dFc_dF, msg.dFc_dF);
  MatrixToArray(model.dFc_dT, msg.dFc_dT);
  MatrixToArray(model.dTc_dF, msg.dTc_dF);
  MatrixToArray(model.dTc_dT, msg.dTc_dT);

  const int n = rows_or_null == nullptr ? 0 : rows_or_null->num_rows();
  msg.num_rows = n;
  msg.num_coupled_rows = 0;
  msg.num_bilateral_rows = 0;
  msg.num_W_body_lower = 0;
  msg.num_W_body_contact_lower = 0;
  msg.rows_per_contact = 1;
  msg.num_friction_coefficients = 0;
  if (n == 0) return msg;
  RowsToMessage(*rows_or_null, &msg);
  return msg;
}

bool FromMessage(const hapsim_lcm::contact_model_t& msg, contact::LinearContactModel* model,
                 contact::ContactRows* rows, ContactModelHeader* header, std::string* error) {
  Eigen::Quaterniond q_WT, visual_q_WT;
  if (!CheckContactModel(msg, error) || !CheckContactRowRanges(msg, error) ||
      !ReadUnitQuaternion(msg.q_WT, "contact_model_t.q_WT", &q_WT, error) ||
      !ReadUnitQuaternion(msg.visual_q_WT, "contact_model_t.visual_q_WT", &visual_q_WT, error)) {
    return false;
  }
  header->utime = msg.utime;
  header->sequence = msg.sequence;
  header->dt_visual_s = msg.dt_visual_s;
  header->dt_haptic_s = msg.dt_haptic_s;
  header->t_frame_s = msg.t_frame_s;
  header->x_W_m = ArrayToVector(msg.x_W_m);
  header->q_WT = q_WT;
  header->visual_tool.x_W_m = ArrayToVector(msg.visual_x_W_m);
  header->visual_tool.q_WT = visual_q_WT;
  header->visual_tool.v_W_m_s = ArrayToVector(msg.visual_v_W_m_s);
  header->visual_tool.L_W_kg_m2_s = ArrayToVector(msg.visual_L_W_kg_m2_s);

  model->num_contacts = msg.num_contacts;
  model->F_c0_N = ArrayToVector(msg.F_c0_N);
  model->T_c0_N_m = ArrayToVector(msg.T_c0_N_m);
  model->dFc_dF = ArrayToMatrix(msg.dFc_dF);
  model->dFc_dT = ArrayToMatrix(msg.dFc_dT);
  model->dTc_dF = ArrayToMatrix(msg.dTc_dF);
  model->dTc_dT = ArrayToMatrix(msg.dTc_dT);
  if (rows == nullptr) return true;

  // resize keeps the storage when the size is unchanged (no allocation; see adapters.h).
  const int n = msg.num_rows;
  const int coupled = msg.num_coupled_rows;
  const int per = std::max<int>(msg.rows_per_contact, 1);
  rows->J_v.resize(n, 3);
  rows->J_w.resize(n, 3);
  rows->W_body.setZero(n, n);  // between blocks that do not travel
  rows->body_rhs.resize(n);
  rows->lambda_frame_N.resize(n);
  for (int i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      rows->J_v(i, c) = msg.J_v[i][c];
      rows->J_w(i, c) = msg.J_w[i][c];
    }
    const int first = contact::FirstRowOfBlock(i, coupled, per);
    for (int c = first; c <= i; ++c)
      rows->W_body(i, c) = rows->W_body(c, i) = PackedBodyEntry(msg, i, c);
    rows->body_rhs[i] = msg.body_rhs[i];
    rows->lambda_frame_N[i] = msg.lambda_frame_N[i];
  }
  rows->gap_m.resize(msg.num_row_gaps);
  rows->gap_target_m_s.resize(msg.num_row_gaps);
  rows->surface_velocity_m_s.resize(msg.num_row_gaps);
  for (int i = 0; i < msg.num_row_gaps; ++i) {
    rows->gap_m[i] = msg.gap_m[i];
    rows->gap_target_m_s[i] = msg.gap_target_m_s[i];
    rows->surface_velocity_m_s[i] = msg.surface_velocity_m_s[i];
  }
  rows->rows_per_contact = per;
  rows->num_uncoupled_rows = n - coupled;
  rows->num_bilateral_rows = msg.num_bilateral_rows;
  rows->friction_coefficient.resize(msg.num_friction_coefficients);
  for (int i = 0; i < msg.num_friction_coefficients; ++i)
    rows->friction_coefficient[i] = msg.friction_coefficient[i];
  StampNewContactRows(rows);
  return true;
}

void WorldToMessage(const Eigen::VectorXd& body_x_m,
                    const std::vector<Eigen::Isometry3d>& object_poses,
                    hapsim_lcm::contact_model_t* msg) {
  const int nodes = static_cast<int>(body_x_m.size() / 3);
  msg->num_body_nodes = nodes;
  msg->body_x_W_m.assign(nodes, std::vector<double>(3));
  for (int i = 0; i < nodes; ++i)
    for (int d = 0; d < 3; ++d) msg->body_x_W_m[i][d] = body_x_m[3 * i + d];
  const int objects = static_cast<int>(object_poses.size());
  msg->num_objects = objects;
  msg->object_x_W_m.assign(objects, std::vector<double>(3));
  msg->object_q_WO.assign(objects, std::vector<double>(4));
  for (int i = 0; i < objects; ++i) {
    VectorToArray(object_poses[i].translation(), msg->object_x_W_m[i].data());
    QuaternionToArray(Eigen::Quaterniond(object_poses[i].linear()), msg->object_q_WO[i].data());
  }
}

bool WorldFromMessage(const hapsim_lcm::contact_model_t& msg, int expected_nodes,
                      int expected_objects, Eigen::VectorXd* body_x_m,
                      std::vector<Eigen::Isometry3d>* object_poses, bool* has_world,
                      std::string* error) {
  *has_world = false;
  if (msg.num_body_nodes == 0 && msg.num_objects == 0) return true;
  if (msg.num_body_nodes < 0 || msg.body_x_W_m.size() != static_cast<size_t>(msg.num_body_nodes) ||
      msg.num_objects < 0 || msg.object_x_W_m.size() != static_cast<size_t>(msg.num_objects) ||
      msg.object_q_WO.size() != static_cast<size_t>(msg.num_objects)) {
    *error = "contact_model_t.num_body_nodes / num_objects: sizes disagree with the counts";
    return false;
  }
  if (msg.num_body_nodes != expected_nodes || msg.num_objects != expected_objects) {
    *error = "contact_model_t: a world of " + std::to_string(msg.num_body_nodes) + " nodes and " +
             std::to_string(msg.num_objects) + " objects, but the scene has " +
             std::to_string(expected_nodes) + " and " + std::to_string(expected_objects);
    return false;
  }
  for (int i = 0; i < msg.num_body_nodes; ++i) {
    if (msg.body_x_W_m[i].size() != 3 ||
        !CheckFinite(msg.body_x_W_m[i].data(), 3, "contact_model_t.body_x_W_m", error))
      return false;
  }
  for (int i = 0; i < msg.num_objects; ++i) {
    Eigen::Quaterniond q;
    if (msg.object_x_W_m[i].size() != 3 || msg.object_q_WO[i].size() != 4 ||
        !CheckFinite(msg.object_x_W_m[i].data(), 3, "contact_model_t.object_x_W_m", error) ||
        !ReadUnitQuaternion(msg.object_q_WO[i].data(), "contact_model_t.object_q_WO", &q, error))
      return false;
  }
  // Valid: copy (resize keeps the storage when the size is unchanged).
  body_x_m->resize(3 * msg.num_body_nodes);
  for (int i = 0; i < msg.num_body_nodes; ++i)
    for (int d = 0; d < 3; ++d) (*body_x_m)[3 * i + d] = msg.body_x_W_m[i][d];
  object_poses->resize(msg.num_objects);
  for (int i = 0; i < msg.num_objects; ++i) {
    Eigen::Quaterniond q;
    ReadUnitQuaternion(msg.object_q_WO[i].data(), "object_q_WO", &q, error);
    (*object_poses)[i] = Eigen::Isometry3d::Identity();
    (*object_poses)[i].linear() = q.toRotationMatrix();
    (*object_poses)[i].translation() = ArrayToVector(msg.object_x_W_m[i].data());
  }
  *has_world = true;
  return true;
}

}  // namespace hapsim::messages
