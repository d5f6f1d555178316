// Bounded decoding of untrusted bytes (messages/wire_decode.h), the run filter
// (messages/message_gate.h) and the bounded LCM log reader (messages/lcm_log_reader.h): the
// hostile inputs of issue 9 are rejected with a message, never a crash or a huge allocation.

#include "messages/wire_decode.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "messages/lcm_log_reader.h"
#include "messages/message_gate.h"

namespace hapsim::messages {
namespace {

template <typename T>
std::vector<std::uint8_t> Encode(const T& msg) {
  std::vector<std::uint8_t> bytes(msg.getEncodedSize());
  EXPECT_EQ(msg.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  return bytes;
}

void PutBigEndian(std::vector<std::uint8_t>* bytes, std::size_t offset, std::uint64_t value,
                  int width) {
  for (int i = 0; i < width; ++i)
    (*bytes)[offset + i] = static_cast<std::uint8_t>(value >> (8 * (width - 1 - i)));
}

hapsim_lcm::contact_model_t MakeContactModel(int rows) {
  hapsim_lcm::contact_model_t msg{};
  msg.run_id = 0x1234;
  msg.dt_visual_s = 0.03;
  msg.dt_haptic_s = 0.001;
  msg.q_WT[0] = msg.visual_q_WT[0] = 1.0;
  msg.num_rows = rows;
  msg.J_v.assign(rows, {0.0, 0.0, -1.0});
  msg.J_w.assign(rows, {0.0, 0.01, 0.0});
  msg.num_coupled_rows = rows;
  msg.num_W_body_lower = rows * (rows + 1) / 2;
  msg.W_body_lower.assign(msg.num_W_body_lower, 0.5);
  msg.body_rhs.assign(rows, 0.1);
  msg.lambda_frame_N.assign(rows, 0.0);
  msg.num_row_gaps = rows;
  msg.gap_m.assign(rows, 1e-3);
  msg.gap_target_m_s.assign(rows, -0.03);
  msg.surface_velocity_m_s.assign(rows, 0.0);
  return msg;
}

hapsim_lcm::sim_frame_t MakeSimFrame() {
  hapsim_lcm::sim_frame_t msg{};
  msg.run_id = 7;
  msg.num_nodes = 4;
  msg.positions_W_m.assign(4, {0.f, 1.f, 2.f});
  msg.num_triangles = 2;
  msg.triangles.assign(2, {0, 1, 2});
  msg.q_WT[0] = 1.0;
  msg.num_contacts = 3;
  msg.p_W_m.assign(3, {0.0, 0.0, 0.0});
  msg.n_W.assign(3, {0.0, 0.0, 1.0});
  msg.lambda_N.assign(3, 1.0);
  msg.contact_kind.assign(3, 0);
  msg.num_objects = 2;
  msg.object_x_W_m.assign(2, {0.0, 0.0, 0.0});
  msg.object_q_WO.assign(2, {1.0, 0.0, 0.0, 0.0});
  msg.selected_object = msg.grabbed_object = -1;
  return msg;
}

hapsim_lcm::run_info_t MakeRunInfo() {
  hapsim_lcm::run_info_t msg{};
  msg.run_id = 99;
  msg.scene_path = "scenes/x.yaml";
  msg.scene_yaml = "name: x\n";
  msg.scene_directory = "/tmp";
  msg.num_files = 2;
  msg.file_paths = {"/a.msh", "/b.stl"};
  msg.file_sha256 = {std::string(64, 'a'), std::string(64, 'b')};
  msg.mode = "linear";
  msg.hapsim_version = "0.1.0";
  return msg;
}

// The hand-written layouts of wire_decode.cc walk every valid message to exactly its end, for
// every type (the generated encoder is the independent value).
TEST(WireDecode, EveryTypeRoundTripsThroughTheLayoutCheck) {
  std::string error;
  {
    hapsim_lcm::device_state_t in{}, out;
    in.run_id = 5;
    in.q_WD[0] = 1.0;
    const auto bytes = Encode(in);
    ASSERT_TRUE(Decode(bytes.data(), bytes.size(), &out, &error)) << error;
    EXPECT_EQ(out.run_id, 5);
  }
  {
    hapsim_lcm::device_force_t in{}, out;
    in.reason = "stale contact model";
    const auto bytes = Encode(in);
    ASSERT_TRUE(Decode(bytes.data(), bytes.size(), &out, &error)) << error;
    EXPECT_EQ(out.reason, in.reason);
  }
  {
    hapsim_lcm::haptic_state_t in{}, out;
    in.reason = "x";
    in.passivity_energy_J = 2.5;
    const auto bytes = Encode(in);
    ASSERT_TRUE(Decode(bytes.data(), bytes.size(), &out, &error)) << error;
    EXPECT_EQ(out.passivity_energy_J, 2.5);
  }
  for (int rows : {0, 1, 7}) {
    hapsim_lcm::contact_model_t out;
    const auto bytes = Encode(MakeContactModel(rows));
    ASSERT_TRUE(Decode(bytes.data(), bytes.size(), &out, &error)) << rows << ": " << error;
    EXPECT_EQ(out.num_rows, rows);
  }
  {
    hapsim_lcm::sim_frame_t out;
    const auto bytes = Encode(MakeSimFrame());
    ASSERT_TRUE(Decode(bytes.data(), bytes.size(), &out, &error)) << error;
    EXPECT_EQ(out.num_contacts, 3);
  }
  {
    hapsim_lcm::run_info_t out;
    const auto bytes = Encode(MakeRunInfo());
    ASSERT_TRUE(Decode(bytes.data(), bytes.size(), &out, &error)) << error;
    EXPECT_EQ(out.file_sha256[1], std::string(64, 'b'));
  }
}

// With no rows and no world a contact model ends in num_rows, num_coupled_rows,
// num_W_body_lower, num_W_body_contact_lower, num_row_gaps (int32), rows_per_contact (int8),
// num_friction_coefficients, num_body_nodes, num_objects, num_bilateral_rows (int32).
std::size_t NumRowsOffset() { return Encode(MakeContactModel(0)).size() - 37; }
std::size_t NumFrictionCoefficientsOffset() { return Encode(MakeContactModel(0)).size() - 16; }
std::size_t NumBodyNodesOffset() { return Encode(MakeContactModel(0)).size() - 12; }

// num_rows = −1 makes lcm-gen's decode() throw (resize to SIZE_MAX) and 10^8 or 2^31 − 1 makes
// it allocate gigabytes before noticing the bytes are missing; Decode refuses all three from the
// count alone.
TEST(WireDecode, HostileRowCountsAreRejectedBeforeDecoding) {
  for (const std::int64_t rows : {-1LL, 100000000LL, 2147483647LL}) {
    auto bytes = Encode(MakeContactModel(0));
    PutBigEndian(&bytes, NumRowsOffset(), static_cast<std::uint64_t>(rows), 4);
    std::string error;
    EXPECT_FALSE(CheckWireLayout<hapsim_lcm::contact_model_t>(bytes.data(), bytes.size(), &error));
    EXPECT_NE(error.find("num_rows"), std::string::npos) << error;
    hapsim_lcm::contact_model_t out;
    EXPECT_FALSE(Decode(bytes.data(), bytes.size(), &out, &error));
    if (rows == -1) {  // the hazard the check removes
      hapsim_lcm::contact_model_t raw;
      EXPECT_ANY_THROW(raw.decode(bytes.data(), 0, static_cast<int>(bytes.size())));
    }
  }
}

// A message decoded into the struct of a previous one (the receive threads reuse theirs): a
// model without rows after one with rows must come out without rows, and be accepted. lcm-gen's
// decode() leaves an array whose count is 0 as it was (it once made the haptic process reject
// every model after the tool lifted off in the lcp mode).
TEST(WireDecode, ACountOfZeroEmptiesTheArrayOfAReusedMessage) {
  hapsim_lcm::contact_model_t reused;
  std::string error;
  const auto with_rows = Encode(MakeContactModel(3));
  ASSERT_TRUE(Decode(with_rows.data(), with_rows.size(), &reused, &error)) << error;
  EXPECT_EQ(reused.W_body_lower.size(), 6u);
  const auto without_rows = Encode(MakeContactModel(0));
  ASSERT_TRUE(Decode(without_rows.data(), without_rows.size(), &reused, &error)) << error;
  EXPECT_EQ(reused.num_rows, 0);
  EXPECT_TRUE(reused.J_v.empty() && reused.J_w.empty() && reused.W_body_lower.empty() &&
              reused.body_rhs.empty() && reused.lambda_frame_N.empty() && reused.gap_m.empty() &&
              reused.gap_target_m_s.empty() && reused.surface_velocity_m_s.empty());
  contact::LinearContactModel model;
  contact::ContactRows rows;
  ContactModelHeader header;
  EXPECT_TRUE(FromMessage(reused, &model, &rows, &header, &error)) << error;
  EXPECT_EQ(rows.num_rows(), 0);
}

// The friction coefficients' count likewise (issue 13: the lcp rows with friction).
TEST(WireDecode, HostileFrictionCountsAreRejectedBeforeDecoding) {
  for (const std::int64_t count : {-1LL, 100000000LL, 2147483647LL}) {
    auto bytes = Encode(MakeContactModel(0));
    PutBigEndian(&bytes, NumFrictionCoefficientsOffset(), static_cast<std::uint64_t>(count), 4);
    std::string error;
    EXPECT_FALSE(CheckWireLayout<hapsim_lcm::contact_model_t>(bytes.data(), bytes.size(), &error));
    EXPECT_NE(error.find("friction"), std::string::npos) << error;
    hapsim_lcm::contact_model_t out;
    EXPECT_FALSE(Decode(bytes.data(), bytes.size(), &out, &error));
  }
}

// The world's node count likewise (docs/HAPTIC_MODES.md): refused from the count alone.
TEST(WireDecode, HostileWorldCountsAreRejectedBeforeDecoding) {
  for (const std::int64_t nodes : {-1LL, 100000000LL, 2147483647LL}) {
    auto bytes = Encode(MakeContactModel(0));
    PutBigEndian(&bytes, NumBodyNodesOffset(), static_cast<std::uint64_t>(nodes), 4);
    std::string error;
    EXPECT_FALSE(CheckWireLayout<hapsim_lcm::contact_model_t>(bytes.data(), bytes.size(), &error));
    EXPECT_NE(error.find("body"), std::string::npos) << error;
    hapsim_lcm::contact_model_t out;
    EXPECT_FALSE(Decode(bytes.data(), bytes.size(), &out, &error));
  }
}

// A string length of 0 (it must count its NUL) makes the generated decode() throw.
TEST(WireDecode, ZeroStringLengthIsRejected) {
  hapsim_lcm::device_force_t in{};
  auto bytes = Encode(in);
  const std::size_t length_offset = bytes.size() - 5;  // the empty reason: int32 1, then NUL
  PutBigEndian(&bytes, length_offset, 0, 4);
  bytes.pop_back();
  hapsim_lcm::device_force_t raw, out;
  EXPECT_ANY_THROW(raw.decode(bytes.data(), 0, static_cast<int>(bytes.size())));
  std::string error;
  EXPECT_FALSE(Decode(bytes.data(), bytes.size(), &out, &error));
  EXPECT_NE(error.find("reason"), std::string::npos) << error;
}

TEST(WireDecode, TruncatedTrailingAndForeignBytesAreRejected) {
  const auto bytes = Encode(MakeSimFrame());
  hapsim_lcm::sim_frame_t out;
  std::string error;
  for (std::size_t cut : {std::size_t{0}, std::size_t{7}, std::size_t{30}, bytes.size() - 1}) {
    EXPECT_FALSE(Decode(bytes.data(), static_cast<int>(cut), &out, &error)) << cut;
  }
  auto longer = bytes;
  longer.push_back(0);
  EXPECT_FALSE(Decode(longer.data(), longer.size(), &out, &error));
  EXPECT_NE(error.find("after the message"), std::string::npos) << error;
  hapsim_lcm::device_state_t other;
  EXPECT_FALSE(Decode(bytes.data(), bytes.size(), &other, &error));  // a sim_frame_t's bytes
  EXPECT_NE(error.find("fingerprint"), std::string::npos) << error;
}

TEST(WireDecode, PeekRunIdReadsEveryTypeAndNothingElse) {
  std::int64_t id = 0;
  const auto frame = Encode(MakeSimFrame());
  ASSERT_TRUE(PeekRunId(frame.data(), frame.size(), &id));
  EXPECT_EQ(id, 7);
  const auto info = Encode(MakeRunInfo());
  ASSERT_TRUE(PeekRunId(info.data(), info.size(), &id));
  EXPECT_EQ(id, 99);
  const auto model = Encode(MakeContactModel(2));
  ASSERT_TRUE(PeekRunId(model.data(), model.size(), &id));
  EXPECT_EQ(id, 0x1234);
  const std::vector<std::uint8_t> junk(64, 0xab);
  EXPECT_FALSE(PeekRunId(junk.data(), junk.size(), &id));
  EXPECT_FALSE(PeekRunId(frame.data(), 20, &id));
}

TEST(MessageGate, AdmitsThisRunCountsOthersAndRejectsGarbage) {
  MessageGate gate("test", 7);
  const auto mine = Encode(MakeSimFrame());  // run 7
  auto other_msg = MakeSimFrame();
  other_msg.run_id = 8;
  const auto other = Encode(other_msg);
  const std::vector<std::uint8_t> junk(40, 0x11);
  hapsim_lcm::sim_frame_t out;
  const auto admit = [&](const std::vector<std::uint8_t>& bytes) {
    const lcm::ReceiveBuffer buffer{const_cast<std::uint8_t*>(bytes.data()),
                                    static_cast<uint32_t>(bytes.size()), 0};
    return gate.Admit(&buffer, "SIM_FRAME", &out);
  };
  EXPECT_TRUE(admit(mine));
  EXPECT_FALSE(admit(other));
  EXPECT_FALSE(admit(other));
  EXPECT_FALSE(admit(junk));
  EXPECT_TRUE(admit(mine));
  EXPECT_EQ(gate.num_foreign(), 2);
  EXPECT_EQ(gate.first_foreign_run(), 8);
  EXPECT_EQ(gate.num_rejected(), 1);
  MessageGate unbound("test", 0);  // no run yet: accepts nothing
  const lcm::ReceiveBuffer buffer{const_cast<std::uint8_t*>(mine.data()),
                                  static_cast<uint32_t>(mine.size()), 0};
  EXPECT_FALSE(unbound.Admit(&buffer, "SIM_FRAME", &out));
}

TEST(RunId, FormatsAndParsesAsHex) {
  std::int64_t id = 0;
  ASSERT_TRUE(ParseRunId(FormatRunId(-2), &id));
  EXPECT_EQ(id, -2);
  ASSERT_TRUE(ParseRunId("0x2A", &id));
  EXPECT_EQ(id, 42);
  EXPECT_FALSE(ParseRunId("0", &id));
  EXPECT_FALSE(ParseRunId("12345678901234567", &id));
  EXPECT_FALSE(ParseRunId("xyz", &id));
  EXPECT_FALSE(ParseRunId("", &id));
  EXPECT_NE(MakeRunId(), 0);
  EXPECT_NE(MakeRunId(), MakeRunId());
}

// ---- the LCM log reader ----

class LogFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = (std::filesystem::temp_directory_path() /
             ("hapsim_log_test_" + std::to_string(::getpid()) + ".lcm"))
                .string();
  }
  void TearDown() override { std::filesystem::remove(path_); }

  // One event in LCM's log format, with lengths as given (not necessarily true).
  static std::vector<std::uint8_t> Event(const std::string& channel, std::size_t data_bytes,
                                         std::int64_t claimed_channel, std::int64_t claimed_data) {
    std::vector<std::uint8_t> bytes(28 + channel.size() + data_bytes, 0x5a);
    PutBigEndian(&bytes, 0, 0xEDA1DA01u, 4);
    PutBigEndian(&bytes, 4, 3, 8);
    PutBigEndian(&bytes, 12, 1700000000000000ULL, 8);
    PutBigEndian(&bytes, 20, static_cast<std::uint64_t>(claimed_channel), 4);
    PutBigEndian(&bytes, 24, static_cast<std::uint64_t>(claimed_data), 4);
    std::copy(channel.begin(), channel.end(), bytes.begin() + 28);
    return bytes;
  }
  void Write(const std::vector<std::uint8_t>& bytes) {
    std::ofstream(path_, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  }
  // The InputError message of reading the whole log, or "" when it reads.
  std::string ReadAllError() {
    try {
      LcmLogReader reader(path_);
      LcmLogEvent event;
      while (reader.Next(&event)) {
      }
      return "";
    } catch (const InputError& e) {
      return e.what();
    }
  }
  std::string path_;
};

TEST_F(LogFileTest, ReadsWellFormedEvents) {
  auto bytes = Event("DEVICE_STATE", 10, 12, 10);
  const auto second = Event("X", 0, 1, 0);
  bytes.insert(bytes.end(), second.begin(), second.end());
  Write(bytes);
  LcmLogReader reader(path_);
  LcmLogEvent event;
  ASSERT_TRUE(reader.Next(&event));
  EXPECT_EQ(event.channel, "DEVICE_STATE");
  EXPECT_EQ(event.data.size(), 10u);
  EXPECT_EQ(event.timestamp_us, 1700000000000000LL);
  ASSERT_TRUE(reader.Next(&event));
  EXPECT_EQ(event.channel, "X");
  EXPECT_EQ(event.offset, 28 + 12 + 10);
  EXPECT_FALSE(reader.Next(&event));
}

// Issue 9: a first event whose data length says 2^31 − 1 made `hapsim replay` segfault inside
// LCM's reader.
TEST_F(LogFileTest, HugeDataLengthIsAnErrorNamingTheByte) {
  Write(Event("DEVICE_STATE", 10, 12, 2147483647));
  const std::string error = ReadAllError();
  EXPECT_NE(error.find(path_), std::string::npos) << error;
  EXPECT_NE(error.find("truncated or corrupt"), std::string::npos) << error;
  EXPECT_NE(error.find("event at byte 0"), std::string::npos) << error;
}

TEST_F(LogFileTest, CorruptHeadersAreErrors) {
  const auto good = Event("A", 4, 1, 4);
  struct Case {
    std::vector<std::uint8_t> bytes;
    const char* expect;
  };
  auto bad_sync = good;
  bad_sync[0] = 0;
  auto cut = good;
  cut.insert(cut.end(), good.begin(), good.begin() + 10);  // a second event cut in its header
  const std::vector<Case> cases = {
      {Event("A", 4, -1, 4), "channel length"},
      {Event("A", 4, 100000, 4), "channel length"},
      {Event("A", 4, 1, -7), "negative data length"},
      {Event("A", 4, 1, 5), "remain"},
      {bad_sync, "sync word"},
      {cut, "event at byte 33"},
  };
  for (const Case& c : cases) {
    Write(c.bytes);
    const std::string error = ReadAllError();
    EXPECT_NE(error.find(c.expect), std::string::npos) << c.expect << ": " << error;
  }
  std::filesystem::remove(path_);
  EXPECT_NE(ReadAllError().find("no such log file"), std::string::npos);
}

}  // namespace
}  // namespace hapsim::messages
