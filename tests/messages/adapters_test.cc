// Round trips core type → message → LCM encode → decode → core type must return the original
// bit for bit (the independent check is the original value itself); inconsistent, non-finite or
// badly normalised messages are rejected naming the field; a contact model crosses an in-process
// memq:// LCM intact.

#include "messages/adapters.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <random>
#include <vector>

#include "messages/wire_decode.h"
#include "tests/allocation_counter.h"

namespace hapsim::messages {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

template <typename Msg>
Msg EncodeDecode(const Msg& msg) {
  const int size = msg.getEncodedSize();
  std::vector<std::uint8_t> buffer(size);
  EXPECT_EQ(msg.encode(buffer.data(), 0, size), size);
  Msg decoded;
  EXPECT_EQ(decoded.decode(buffer.data(), 0, size), size);
  return decoded;
}

// Same shape and the same bits (stricter than ==, which equates −0 and +0).
template <typename A, typename B>
void ExpectBitIdentical(const A& a, const B& b, const char* what) {
  ASSERT_EQ(a.rows(), b.rows()) << what;
  ASSERT_EQ(a.cols(), b.cols()) << what;
  // An empty matrix's data() is null, which memcmp must not be given even for 0 bytes.
  if (a.size() > 0) {
    EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof(double) * a.size()), 0) << what;
  }
}

void ExpectBitIdentical(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b,
                        const char* what) {
  ExpectBitIdentical(a.coeffs(), b.coeffs(), what);
}

struct Random {
  std::mt19937 engine{20240607};
  std::uniform_real_distribution<double> uniform{-1.0, 1.0};
  double operator()() { return uniform(engine); }
  Eigen::Vector3d Vector() { return {(*this)(), (*this)(), (*this)()}; }
  Eigen::Matrix3d Matrix() {
    return Eigen::Matrix3d::NullaryExpr([this] { return (*this)(); });
  }
  Eigen::Quaterniond Rotation() {
    return Eigen::Quaterniond((*this)(), (*this)(), (*this)(), (*this)()).normalized();
  }
};

TEST(DeviceStateMessage, RoundTripIsBitIdentical) {
  Random random;
  DeviceState device;
  device.x_W_m = random.Vector();
  device.q_WD = random.Rotation();
  device.v_W_m_s = random.Vector();
  device.w_W_rad_s = random.Vector();
  device.buttons = 0b101;
  const auto msg = EncodeDecode(ToMessage(device, 1717000000123456, 42));
  EXPECT_EQ(msg.utime, 1717000000123456);
  EXPECT_EQ(msg.sequence, 42);
  EXPECT_EQ(msg.buttons, 0b101);
  DeviceState out;
  std::string error;
  ASSERT_TRUE(FromMessage(msg, &out, &error)) << error;
  ExpectBitIdentical(out.x_W_m, device.x_W_m, "x_W_m");
  ExpectBitIdentical(out.q_WD, device.q_WD, "q_WD");
  ExpectBitIdentical(out.v_W_m_s, device.v_W_m_s, "v_W_m_s");
  ExpectBitIdentical(out.w_W_rad_s, device.w_W_rad_s, "w_W_rad_s");
  EXPECT_EQ(out.buttons, device.buttons);
}

// The safety layer, not the adapter, answers a NaN device state (with zero force).
TEST(DeviceStateMessage, NonFiniteValuesPassThrough) {
  hapsim_lcm::device_state_t msg = ToMessage(DeviceState(), 0, 0);
  msg.x_W_m[1] = kNaN;
  msg.v_W_m_s[0] = std::numeric_limits<double>::infinity();
  for (double& q : msg.q_WD) q = kNaN;
  DeviceState out;
  std::string error;
  ASSERT_TRUE(FromMessage(msg, &out, &error)) << error;
  EXPECT_TRUE(std::isnan(out.x_W_m.y()));
  EXPECT_TRUE(std::isinf(out.v_W_m_s.x()));
  EXPECT_TRUE(std::isnan(out.q_WD.w()));
}

TEST(DeviceStateMessage, QuaternionIsNormalisedOrRejected) {
  hapsim_lcm::device_state_t msg = ToMessage(DeviceState(), 0, 0);
  const double slightly_off = 1.0 + 0.5 * kQuaternionNormTolerance;
  msg.q_WD[0] = 0.6 * slightly_off;
  msg.q_WD[3] = 0.8 * slightly_off;
  DeviceState out;
  std::string error;
  ASSERT_TRUE(FromMessage(msg, &out, &error)) << error;
  EXPECT_NEAR(out.q_WD.norm(), 1.0, 1e-15);
  EXPECT_NEAR(out.q_WD.z(), 0.8, 1e-15);

  msg.q_WD[0] = 1.1;  // norm ≈ 1.36
  out.x_W_m = Eigen::Vector3d(7.0, 7.0, 7.0);
  EXPECT_FALSE(FromMessage(msg, &out, &error));
  EXPECT_NE(error.find("q_WD"), std::string::npos) << error;
  EXPECT_EQ(out.x_W_m, Eigen::Vector3d(7.0, 7.0, 7.0)) << "outputs untouched on failure";
}

TEST(DeviceForceMessage, RoundTripZeroingAndRejection) {
  Random random;
  const Eigen::Vector3d force = random.Vector(), torque = random.Vector();
  auto msg = EncodeDecode(ToMessage(force, torque, 5, 6));
  EXPECT_EQ(msg.sequence, 6);
  EXPECT_FALSE(msg.zeroed);
  Eigen::Vector3d force_out, torque_out;
  std::string error;
  ASSERT_TRUE(FromMessage(msg, &force_out, &torque_out, &error)) << error;
  ExpectBitIdentical(force_out, force, "force_W_N");
  ExpectBitIdentical(torque_out, torque, "torque_W_N_m");

  msg = EncodeDecode(ToMessage(force, torque, 5, 7, "stale contact model"));
  EXPECT_TRUE(msg.zeroed);
  EXPECT_EQ(msg.reason, "stale contact model");
  ASSERT_TRUE(FromMessage(msg, &force_out, &torque_out, &error)) << error;
  EXPECT_EQ(force_out, Eigen::Vector3d::Zero());
  EXPECT_EQ(torque_out, Eigen::Vector3d::Zero());

  msg.force_W_N[2] = kNaN;
  EXPECT_FALSE(FromMessage(msg, &force_out, &torque_out, &error));
  EXPECT_NE(error.find("force_W_N"), std::string::npos) << error;
}

TEST(ToolPoseMessage, RoundTripThroughHapticStateAndSimFrame) {
  Random random;
  ToolState tool;
  tool.x_W_m = random.Vector();
  tool.q_WT = random.Rotation();
  hapsim_lcm::haptic_state_t haptic{};
  PoseToMessage(tool, haptic.x_W_m, haptic.q_WT);
  haptic.reason = "non-finite device state";
  hapsim_lcm::sim_frame_t frame{};
  PoseToMessage(tool, frame.x_W_m, frame.q_WT);
  frame.num_nodes = 2;
  frame.positions_W_m = {{0.1f, 0.2f, 0.3f}, {-0.1f, 1e-7f, 0.05f}};
  frame.num_triangles = 1;
  frame.triangles = {{0, 1, 0}};
  frame.num_contacts = 1;
  frame.p_W_m = {{0.01, 0.02, 0.03}};
  frame.n_W = {{0.0, 0.0, -1.0}};
  frame.lambda_N = {2.5};
  frame.contact_kind = {2};
  frame.num_objects = 1;
  frame.object_x_W_m = {{0.0, 0.0, -0.005}};
  frame.object_q_WO = {{1.0, 0.0, 0.0, 0.0}};
  frame.selected_object = -1;
  frame.grabbed_object = 0;

  const auto haptic_out = EncodeDecode(haptic);
  const auto frame_out = EncodeDecode(frame);
  EXPECT_EQ(haptic_out.reason, haptic.reason);
  EXPECT_EQ(frame_out.positions_W_m, frame.positions_W_m);
  EXPECT_EQ(frame_out.triangles, frame.triangles);
  EXPECT_EQ(frame_out.lambda_N, frame.lambda_N);
  EXPECT_EQ(frame_out.contact_kind, frame.contact_kind);
  EXPECT_EQ(frame_out.object_x_W_m, frame.object_x_W_m);
  EXPECT_EQ(frame_out.object_q_WO, frame.object_q_WO);
  EXPECT_EQ(frame_out.grabbed_object, 0);
  const auto expect_pose = [&](const double x_W_m[3], const double q_WT[4], const char* what) {
    ToolState out;
    out.v_W_m_s = Eigen::Vector3d(1.0, 2.0, 3.0);
    std::string error;
    ASSERT_TRUE(PoseFromMessage(x_W_m, q_WT, &out, &error)) << what << ": " << error;
    ExpectBitIdentical(out.x_W_m, tool.x_W_m, what);
    ExpectBitIdentical(out.q_WT, tool.q_WT, what);
    EXPECT_EQ(out.v_W_m_s, Eigen::Vector3d(1.0, 2.0, 3.0)) << "velocity is not part of the pose";
  };
  expect_pose(haptic_out.x_W_m, haptic_out.q_WT, "haptic_state_t");
  expect_pose(frame_out.x_W_m, frame_out.q_WT, "sim_frame_t");

  double bad_q[4] = {0.0, 0.0, 0.0, 0.0};
  ToolState out;
  std::string error;
  EXPECT_FALSE(PoseFromMessage(haptic_out.x_W_m, bad_q, &out, &error));
  EXPECT_NE(error.find("q_WT"), std::string::npos) << error;
}

TEST(RunInfoMessage, SceneTextSurvivesEncoding) {
  hapsim_lcm::run_info_t info{};
  info.scene_yaml = "body:\n  mesh: \"meshes/block.msh\"  # ünïcode, tabs\t\n";
  info.mode = "lcp";
  info.haptic_rate_hz = 1000.0;
  const auto out = EncodeDecode(info);
  EXPECT_EQ(out.scene_yaml, info.scene_yaml);
  EXPECT_EQ(out.mode, "lcp");
  EXPECT_EQ(out.haptic_rate_hz, 1000.0);
}

struct ContactModelFixture {
  contact::LinearContactModel model;
  contact::ContactRows rows;
  ContactModelHeader header;

  explicit ContactModelFixture(int num_rows) {
    Random random;
    model.F_c0_N = random.Vector();
    model.T_c0_N_m = random.Vector();
    model.dFc_dF = random.Matrix();
    model.dFc_dT = random.Matrix();
    model.dTc_dF = random.Matrix();
    model.dTc_dT = random.Matrix();
    model.num_contacts = num_rows + 1;
    // J_v,i = −n_iᵀ: unit rows, as every sender makes them (FromMessage checks).
    rows.J_v = Eigen::MatrixX3d::NullaryExpr(num_rows, 3, [&] { return random(); });
    rows.J_v.rowwise().normalize();
    rows.J_w = Eigen::MatrixX3d::NullaryExpr(num_rows, 3, [&] { return random(); });
    const Eigen::MatrixXd A =
        Eigen::MatrixXd::NullaryExpr(num_rows, num_rows, [&] { return random(); });
    const Eigen::MatrixXd AAt = A * A.transpose();
    rows.W_body = 0.5 * (AAt + AAt.transpose());  // exactly symmetric, as MakeContactRows makes it
    rows.body_rhs = Eigen::VectorXd::NullaryExpr(num_rows, [&] { return random(); });
    rows.lambda_frame_N =
        Eigen::VectorXd::NullaryExpr(num_rows, [&] { return std::max(0.0, random()); });
    rows.gap_m = Eigen::VectorXd::NullaryExpr(num_rows, [&] { return 1e-3 * random(); });
    rows.gap_target_m_s = Eigen::VectorXd::NullaryExpr(num_rows, [&] { return random(); });
    rows.surface_velocity_m_s = Eigen::VectorXd::NullaryExpr(num_rows, [&] { return random(); });
    header = {1717000000000001,  99,         1.0 / 60.0, 1e-3, 1.65, random.Vector(),
              random.Rotation(), ToolState{}};
    header.visual_tool.x_W_m = random.Vector();
    header.visual_tool.q_WT = random.Rotation();
    header.visual_tool.v_W_m_s = random.Vector();
    header.visual_tool.L_W_kg_m2_s = random.Vector();
  }
};

void ExpectSameModel(const contact::LinearContactModel& a, const contact::LinearContactModel& b) {
  ExpectBitIdentical(a.F_c0_N, b.F_c0_N, "F_c0_N");
  ExpectBitIdentical(a.T_c0_N_m, b.T_c0_N_m, "T_c0_N_m");
  ExpectBitIdentical(a.dFc_dF, b.dFc_dF, "dFc_dF");
  ExpectBitIdentical(a.dFc_dT, b.dFc_dT, "dFc_dT");
  ExpectBitIdentical(a.dTc_dF, b.dTc_dF, "dTc_dF");
  ExpectBitIdentical(a.dTc_dT, b.dTc_dT, "dTc_dT");
  EXPECT_EQ(a.num_contacts, b.num_contacts);
}

void ExpectSameRowsAndHeader(const ContactModelFixture& in, const contact::ContactRows& rows,
                             const ContactModelHeader& header) {
  ExpectBitIdentical(rows.J_v, in.rows.J_v, "J_v");
  ExpectBitIdentical(rows.J_w, in.rows.J_w, "J_w");
  ExpectBitIdentical(rows.W_body, in.rows.W_body, "W_body");
  ExpectBitIdentical(rows.body_rhs, in.rows.body_rhs, "body_rhs");
  ExpectBitIdentical(rows.lambda_frame_N, in.rows.lambda_frame_N, "lambda_frame_N");
  ExpectBitIdentical(rows.gap_m, in.rows.gap_m, "gap_m");
  ExpectBitIdentical(rows.gap_target_m_s, in.rows.gap_target_m_s, "gap_target_m_s");
  ExpectBitIdentical(rows.surface_velocity_m_s, in.rows.surface_velocity_m_s,
                     "surface_velocity_m_s");
  EXPECT_EQ(rows.rows_per_contact, in.rows.rows_per_contact);
  EXPECT_EQ(rows.num_uncoupled_rows, in.rows.num_uncoupled_rows);
  ExpectBitIdentical(rows.friction_coefficient, in.rows.friction_coefficient,
                     "friction_coefficient");
  EXPECT_EQ(header.utime, in.header.utime);
  EXPECT_EQ(header.sequence, in.header.sequence);
  EXPECT_EQ(header.dt_visual_s, in.header.dt_visual_s);
  EXPECT_EQ(header.dt_haptic_s, in.header.dt_haptic_s);
  EXPECT_EQ(header.t_frame_s, in.header.t_frame_s);
  ExpectBitIdentical(header.x_W_m, in.header.x_W_m, "x_W_m");
  ExpectBitIdentical(header.q_WT, in.header.q_WT, "q_WT");
  ExpectBitIdentical(header.visual_tool.x_W_m, in.header.visual_tool.x_W_m, "visual_x_W_m");
  ExpectBitIdentical(header.visual_tool.q_WT, in.header.visual_tool.q_WT, "visual_q_WT");
  ExpectBitIdentical(header.visual_tool.v_W_m_s, in.header.visual_tool.v_W_m_s, "visual_v_W_m_s");
  ExpectBitIdentical(header.visual_tool.L_W_kg_m2_s, in.header.visual_tool.L_W_kg_m2_s,
                     "visual_L_W_kg_m2_s");
}

TEST(ContactModelMessage, RoundTripWithRowsIsBitIdentical) {
  const ContactModelFixture in(5);
  const auto msg = EncodeDecode(ToMessage(in.model, &in.rows, in.header));
  // Row-major layout, checked on an off-diagonal entry of each asymmetric array.
  EXPECT_EQ(msg.dFc_dT[1][2], in.model.dFc_dT(1, 2));
  EXPECT_EQ(msg.J_w[4][0], in.rows.J_w(4, 0));
  contact::LinearContactModel model;
  contact::ContactRows rows;
  ContactModelHeader header;
  std::string error;
  ASSERT_TRUE(FromMessage(msg, &model, &rows, &header, &error)) << error;
  ExpectSameModel(model, in.model);
  ExpectSameRowsAndHeader(in, rows, header);
}

// Friction rows (issue 13): three rows per contact, a μ per contact, and tangential impulses of
// either sign travel unchanged; a layout that does not add up is refused naming the field.
TEST(ContactModelMessage, FrictionRowsRoundTripAndBadLayoutsAreRejected) {
  ContactModelFixture in(6);
  in.rows.rows_per_contact = 3;
  in.rows.friction_coefficient = Eigen::Vector2d(0.3, 0.0);
  in.rows.lambda_frame_N[1] = -0.25;  // a tangential impulse
  const auto msg = EncodeDecode(ToMessage(in.model, &in.rows, in.header));
  EXPECT_EQ(msg.rows_per_contact, 3);
  contact::LinearContactModel model;
  contact::ContactRows rows;
  ContactModelHeader header;
  std::string error;
  ASSERT_TRUE(FromMessage(msg, &model, &rows, &header, &error)) << error;
  ExpectSameRowsAndHeader(in, rows, header);
  struct Case {
    const char* field;
    std::function<void(hapsim_lcm::contact_model_t*)> corrupt;
  };
  const std::vector<Case> cases = {
      {"rows_per_contact", [](auto* m) { m->rows_per_contact = 2; }},
      {"friction_coefficient", [](auto* m) { m->friction_coefficient.pop_back(); }},
      {"friction_coefficient[1]", [](auto* m) { m->friction_coefficient[1] = -0.1; }},
      {"friction_coefficient", [](auto* m) { m->friction_coefficient[0] = kNaN; }},
      {"lambda_frame_N[3]", [](auto* m) { m->lambda_frame_N[3] = -0.5; }},  // a normal row
      {"num_row_gaps", [](auto* m) { m->num_row_gaps = 1; }},
      {"gap_m", [](auto* m) { m->gap_m[2] = kNaN; }},
      {"gap_target_m_s", [](auto* m) { m->gap_target_m_s.pop_back(); }},
      {"surface_velocity_m_s", [](auto* m) { m->surface_velocity_m_s[0] = kNaN; }},
  };
  for (const Case& c : cases) {
    hapsim_lcm::contact_model_t bad = msg;
    c.corrupt(&bad);
    error.clear();
    EXPECT_FALSE(FromMessage(bad, &model, &rows, &header, &error)) << c.field;
    EXPECT_NE(error.find(c.field), std::string::npos) << c.field << ": " << error;
  }
  // Rows whose μ count does not match are refused at the sender.
  in.rows.friction_coefficient = Eigen::Vector3d(0.3, 0.3, 0.3);
  EXPECT_THROW(ToMessage(in.model, &in.rows, in.header), std::invalid_argument);
}

// Only W_body's lower triangle is sent: the upper one is rebuilt from it, so an asymmetric
// matrix (which would arrive changed) is refused at the sender.
TEST(ContactModelMessage, PackedLowerTriangleHasTheExpectedLayout) {
  const ContactModelFixture in(4);
  const auto msg = ToMessage(in.model, &in.rows, in.header);
  ASSERT_EQ(msg.num_W_body_lower, 10);
  EXPECT_EQ(msg.W_body_lower[0], in.rows.W_body(0, 0));
  EXPECT_EQ(msg.W_body_lower[4], in.rows.W_body(2, 1));  // row 2 starts at 2·3/2 = 3
  EXPECT_EQ(msg.W_body_lower[9], in.rows.W_body(3, 3));
  ContactModelFixture asymmetric(4);
  asymmetric.rows.W_body(0, 3) += 1e-15;
  EXPECT_THROW(ToMessage(asymmetric.model, &asymmetric.rows, asymmetric.header),
               std::invalid_argument);
}

// Contacts declared uncoupled (ContactRows::num_uncoupled_rows; issue 13 item 5: the visual
// frame sends them last) travel as their own blocks: of 12 contacts, the last 6 uncoupled arrive
// bit for bit after the packed triangle of the first 6 contacts' rows, one block each (1 entry
// with normal rows, 6 with friction's threes). A W_body not zero where the rows declare it is
// refused at the sender, and the new fields' inconsistencies at the receiver, by name.
TEST(ContactModelMessage, UncoupledContactsTravelAsTheirOwnBlocks) {
  for (const int per : {1, 3}) {
    SCOPED_TRACE(per);
    const int n = 12 * per, coupled = 6 * per;
    ContactModelFixture in(n);
    in.rows.rows_per_contact = per;
    if (per == 3) in.rows.friction_coefficient = Eigen::VectorXd::LinSpaced(12, 0.0, 1.1);
    in.rows.num_uncoupled_rows = n - coupled;
    EXPECT_THROW(ToMessage(in.model, &in.rows, in.header), std::invalid_argument);
    for (int r = coupled; r < n; ++r)
      for (int c = 0; c < n; ++c)
        if (c < r - (r - coupled) % per || c >= r - (r - coupled) % per + per)
          in.rows.W_body(r, c) = in.rows.W_body(c, r) = 0.0;
    const auto msg = EncodeDecode(ToMessage(in.model, &in.rows, in.header));
    EXPECT_EQ(msg.num_coupled_rows, coupled);
    EXPECT_EQ(msg.num_W_body_lower, coupled * (coupled + 1) / 2);
    EXPECT_EQ(msg.num_W_body_contact_lower, 6 * per * (per + 1) / 2);
    EXPECT_EQ(msg.W_body_contact_lower[0], in.rows.W_body(coupled, coupled));
    if (per == 3) {
      EXPECT_EQ(msg.W_body_contact_lower[4], in.rows.W_body(20, 19));  // [t2][t1]
      EXPECT_EQ(msg.W_body_contact_lower[6], in.rows.W_body(21, 21));  // the next contact
    }
    contact::LinearContactModel model;
    contact::ContactRows rows = ContactModelFixture(n).rows;  // stale, every entry non-zero
    ContactModelHeader header;
    std::string error;
    ASSERT_TRUE(FromMessage(msg, &model, &rows, &header, &error)) << error;
    ExpectBitIdentical(rows.W_body, in.rows.W_body, "W_body");
    ExpectSameRowsAndHeader(in, rows, header);

    const std::vector<std::pair<const char*, std::function<void(hapsim_lcm::contact_model_t*)>>>
        cases = {{"num_coupled_rows", [n](auto* m) { m->num_coupled_rows = n + 3; }},
                 {"num_coupled_rows", [](auto* m) { m->num_coupled_rows = -3; }},
                 {"W_body_lower", [per](auto* m) { m->num_coupled_rows += per; }},
                 {"W_body_contact_lower", [](auto* m) { m->W_body_contact_lower.pop_back(); }},
                 {"W_body_contact_lower", [](auto* m) { m->W_body_contact_lower[0] = kNaN; }},
                 {"W_body_contact_lower", [](auto* m) { m->W_body_contact_lower[0] = -1e-9; }},
                 // A grasp's rows: within the coupled rows, never negative, normal rows only.
                 {"num_bilateral_rows", [](auto* m) { m->num_bilateral_rows = -1; }},
                 {"num_bilateral_rows",
                  [](auto* m) { m->num_bilateral_rows = m->num_coupled_rows + 1; }},
                 {"num_bilateral_rows",
                  [per](auto* m) { m->num_bilateral_rows = per == 3 ? 3 : m->num_rows + 1; }},
                 // Without them a normal row's frame impulse cannot pull.
                 {"lambda_frame_N", [](auto* m) { m->lambda_frame_N[0] = -0.1; }}};
    for (const auto& [field, corrupt] : cases) {
      hapsim_lcm::contact_model_t bad = msg;
      corrupt(&bad);
      EXPECT_FALSE(FromMessage(bad, &model, &rows, &header, &error)) << field;
      EXPECT_NE(error.find(field), std::string::npos) << field << ": " << error;
    }
  }
}

TEST(ContactModelMessage, RoundTripWithoutRowsEmptiesTheRows) {
  const ContactModelFixture in(0);
  const auto msg = EncodeDecode(ToMessage(in.model, nullptr, in.header));
  EXPECT_EQ(msg.num_rows, 0);
  contact::LinearContactModel model;
  contact::ContactRows rows = ContactModelFixture(3).rows;  // stale rows of an older frame
  ContactModelHeader header;
  std::string error;
  ASSERT_TRUE(FromMessage(msg, &model, &rows, &header, &error)) << error;
  ExpectSameModel(model, in.model);
  ExpectSameRowsAndHeader(in, rows, header);
}

// The frame's world of the geometric modes (docs/HAPTIC_MODES.md): bit-identical through the
// wire; a message without one says so; a wrong size for the scene, a NaN or a bad quaternion is
// refused with the field's name, the outputs untouched.
TEST(ContactModelMessage, WorldRoundTripAndRejections) {
  const ContactModelFixture in(0);
  Eigen::VectorXd body_x_m(9);
  body_x_m << 0.1, -0.2, 0.3, 1e-7, 2.5, -3.0, 0.0, 0.01, 1.0 / 3.0;
  std::vector<Eigen::Isometry3d> poses(2, Eigen::Isometry3d::Identity());
  poses[1].translation() = Eigen::Vector3d(0.01, 0.02, -0.03);
  poses[1].linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).matrix();
  hapsim_lcm::contact_model_t msg = ToMessage(in.model, nullptr, in.header);
  WorldToMessage(body_x_m, poses, &msg);
  msg = EncodeDecode(msg);
  Eigen::VectorXd x_out;
  std::vector<Eigen::Isometry3d> poses_out;
  bool has_world = false;
  std::string error;
  ASSERT_TRUE(WorldFromMessage(msg, 3, 2, &x_out, &poses_out, &has_world, &error)) << error;
  EXPECT_TRUE(has_world);
  ExpectBitIdentical(x_out, body_x_m, "body_x_W_m");
  ASSERT_EQ(poses_out.size(), 2u);
  EXPECT_TRUE(poses_out[1].translation() == poses[1].translation());
  EXPECT_LT((poses_out[1].linear() - poses[1].linear()).norm(), 1e-15);
  // No world: nothing read, nothing changed.
  const auto without = EncodeDecode(ToMessage(in.model, nullptr, in.header));
  ASSERT_TRUE(WorldFromMessage(without, 3, 2, &x_out, &poses_out, &has_world, &error));
  EXPECT_FALSE(has_world);
  // Refusals, each naming what is wrong.
  struct Case {
    const char* what;
    std::function<void(hapsim_lcm::contact_model_t*)> spoil;
  };
  const Case cases[] = {
      {"the scene has",
       [](hapsim_lcm::contact_model_t* m) {
         m->num_body_nodes = 2;
         m->body_x_W_m.pop_back();
       }},
      {"body_x_W_m", [](hapsim_lcm::contact_model_t* m) { m->body_x_W_m[1][2] = NAN; }},
      {"object_q_WO", [](hapsim_lcm::contact_model_t* m) { m->object_q_WO[0][0] = 2.0; }},
      {"sizes disagree", [](hapsim_lcm::contact_model_t* m) { m->object_x_W_m.pop_back(); }},
  };
  for (const Case& c : cases) {
    hapsim_lcm::contact_model_t bad = msg;
    c.spoil(&bad);
    Eigen::VectorXd x_kept = Eigen::VectorXd::Constant(9, 7.0);
    std::vector<Eigen::Isometry3d> poses_kept(2, Eigen::Isometry3d::Identity());
    error.clear();
    EXPECT_FALSE(WorldFromMessage(bad, 3, 2, &x_kept, &poses_kept, &has_world, &error)) << c.what;
    EXPECT_NE(error.find(c.what), std::string::npos) << error;
    EXPECT_EQ(x_kept, Eigen::VectorXd::Constant(9, 7.0)) << c.what;
  }
}

TEST(ContactModelMessage, InconsistentOrNonFiniteMessagesAreRejected) {
  const ContactModelFixture in(3);
  const hapsim_lcm::contact_model_t good = ToMessage(in.model, &in.rows, in.header);
  struct Case {
    const char* field;  // must appear in the error
    std::function<void(hapsim_lcm::contact_model_t*)> corrupt;
  };
  const std::vector<Case> cases = {
      {"J_v", [](auto* m) { m->J_v.pop_back(); }},
      {"J_v", [](auto* m) { m->num_rows = 4; }},
      {"J_w", [](auto* m) { m->J_w.pop_back(); }},
      {"W_body_lower", [](auto* m) { m->W_body_lower.pop_back(); }},
      {"W_body_lower", [](auto* m) { m->num_W_body_lower = 9; }},
      {"body_rhs", [](auto* m) { m->body_rhs.push_back(0.0); }},
      {"num_rows", [](auto* m) { m->num_rows = -1; }},
      {"num_contacts", [](auto* m) { m->num_contacts = -2; }},
      {"dFc_dT", [](auto* m) { m->dFc_dT[1][2] = kNaN; }},
      {"F_c0_N", [](auto* m) { m->F_c0_N[0] = std::numeric_limits<double>::infinity(); }},
      {"J_w[1]", [](auto* m) { m->J_w[1][2] = kNaN; }},
      {"W_body_lower", [](auto* m) { m->W_body_lower[4] = kNaN; }},
      {"body_rhs", [](auto* m) { m->body_rhs[2] = kNaN; }},
      {"lambda_frame_N", [](auto* m) { m->lambda_frame_N[1] = kNaN; }},
      {"x_W_m", [](auto* m) { m->x_W_m[0] = kNaN; }},
      {"q_WT", [](auto* m) { m->q_WT[0] *= 0.5; }},
      {"dt_haptic_s", [](auto* m) { m->dt_haptic_s = 0.0; }},
      {"dt_visual_s", [](auto* m) { m->dt_visual_s = kNaN; }},
      // Ranges (issue 9): a normal that is not unit, a W_body that cannot be positive
      // semidefinite, an impulse that pulls.
      {"J_v[2]", [](auto* m) { m->J_v[2][0] += 0.01; }},
      {"J_v[1]",
       [](auto* m) {
         m->J_v[1] = {0.0, 0.0, 0.0};
       }},                                                            // zero, but J_w is not
      {"W_body_lower", [](auto* m) { m->W_body_lower[2] = -1e-9; }},  // diagonal of row 1
      {"lambda_frame_N[0]", [](auto* m) { m->lambda_frame_N[0] = -0.5; }},
  };
  for (const Case& c : cases) {
    hapsim_lcm::contact_model_t msg = good;
    c.corrupt(&msg);
    const ContactModelFixture before(2);  // outputs must keep these values
    contact::LinearContactModel model = before.model;
    contact::ContactRows rows = before.rows;
    ContactModelHeader header = before.header;
    std::string error;
    EXPECT_FALSE(FromMessage(msg, &model, &rows, &header, &error)) << c.field;
    EXPECT_NE(error.find(c.field), std::string::npos) << c.field << ": " << error;
    ExpectSameModel(model, before.model);
    ExpectSameRowsAndHeader(before, rows, header);
  }
}

// A row that touches no tool (a body node on a rigid object, as the lcp and hybrid rows of a
// scene with a tray carry): J_v and J_w zero. It travels; the train_test's liver on its tray once
// found every such model refused by the unit-normal check.
TEST(ContactModelMessage, RowsThatTouchNoToolTravel) {
  ContactModelFixture in(4);
  in.rows.J_v.row(2).setZero();
  in.rows.J_w.row(2).setZero();
  const auto msg = ToMessage(in.model, &in.rows, in.header);
  contact::LinearContactModel model;
  contact::ContactRows rows;
  ContactModelHeader header;
  std::string error;
  ASSERT_TRUE(FromMessage(msg, &model, &rows, &header, &error)) << error;
  ExpectSameRowsAndHeader(in, rows, header);
}

// The receive thread refills the same ContactRows every frame; with an unchanged row count
// that must not touch the heap.
TEST(ContactModelMessage, RowStorageIsReusedWhenTheSizeIsUnchanged) {
  const ContactModelFixture first(6), second(6);
  const auto msg1 = ToMessage(first.model, &first.rows, first.header);
  auto msg2 = ToMessage(second.model, &second.rows, second.header);
  msg2.W_body_lower[0] += 1.0;  // a different frame's values
  contact::LinearContactModel model;
  contact::ContactRows rows;
  ContactModelHeader header;
  std::string error;
  ASSERT_TRUE(FromMessage(msg1, &model, &rows, &header, &error)) << error;
  const std::uint64_t first_stamp = rows.stamp;
  const double* W_storage = rows.W_body.data();
  const double* J_storage = rows.J_v.data();
  AllocationCounter counter;
  ASSERT_TRUE(FromMessage(msg2, &model, &rows, &header, &error)) << error;
  const std::int64_t allocations = counter.count();
  EXPECT_EQ(rows.W_body.data(), W_storage);
  EXPECT_EQ(rows.J_v.data(), J_storage);
  EXPECT_EQ(rows.W_body(0, 0), msg2.W_body_lower[0]);
  // Each decode is new rows to the haptic solvers (ContactRows::stamp).
  EXPECT_NE(first_stamp, 0u);
  EXPECT_NE(rows.stamp, first_stamp);
  if (!AllocationCounter::enabled()) GTEST_SKIP() << "allocations not counted (sanitizer)";
  EXPECT_EQ(allocations, 0);
}

// Receives as the haptic process does: raw bytes through the bounded decoder (wire_decode.h).
struct ContactModelReceiver {
  int count = 0;
  std::string channel;
  hapsim_lcm::contact_model_t msg;
  std::string error;
  void Handle(const lcm::ReceiveBuffer* buffer, const std::string& chan) {
    if (!Decode(buffer->data, static_cast<int>(buffer->data_size), &msg, &error)) return;
    ++count;
    channel = chan;
  }
};

TEST(ContactModelMessage, CrossesInProcessLcmIntact) {
  lcm::LCM lcm("memq://");  // in-process queue only: tests never touch the network
  ASSERT_TRUE(lcm.good());
  ContactModelReceiver receiver;
  lcm.subscribe("CONTACT_MODEL", &ContactModelReceiver::Handle, &receiver);
  const ContactModelFixture in(4);
  const auto sent = ToMessage(in.model, &in.rows, in.header);
  ASSERT_EQ(lcm.publish("CONTACT_MODEL", &sent), 0);
  ASSERT_GT(lcm.handleTimeout(1000), 0);
  ASSERT_EQ(receiver.count, 1) << receiver.error;
  EXPECT_EQ(receiver.channel, "CONTACT_MODEL");
  contact::LinearContactModel model;
  contact::ContactRows rows;
  ContactModelHeader header;
  std::string error;
  ASSERT_TRUE(FromMessage(receiver.msg, &model, &rows, &header, &error)) << error;
  ExpectSameModel(model, in.model);
  ExpectSameRowsAndHeader(in, rows, header);
}

}  // namespace
}  // namespace hapsim::messages
