#include "messages/wire_decode.h"

#include <cstring>

namespace hapsim::messages {
namespace {

// A read position in untrusted bytes. Every step checks what remains (in 64 bits, so no count
// product can overflow); the first failure is kept and every later step is a no-op.
class WireCursor {
 public:
  WireCursor(const void* data, int size, const char* type)
      : data_(static_cast<const std::uint8_t*>(data)), size_(size < 0 ? 0 : size), type_(type) {}

  // The type fingerprint: the first 8 bytes must be T's.
  void ExpectHash(std::int64_t hash) {
    if (!Need(8, "fingerprint")) return;
    if (ReadBigEndian(8) != static_cast<std::uint64_t>(hash))
      return Fail("fingerprint", "not this type");
    position_ += 8;
  }
  // `count` elements of `bytes_each` bytes (a fixed-size field is one element).
  void Skip(std::int64_t count, std::int64_t bytes_each, const char* field) {
    if (count < 0) return Fail(field, "negative count " + std::to_string(count));
    if (Need(count * bytes_each, field)) position_ += count * bytes_each;
  }
  // An int32 count field; -1 after a failure.
  std::int64_t ReadCount(const char* field) {
    if (!Need(4, field)) return -1;
    const auto value = static_cast<std::int32_t>(static_cast<std::uint32_t>(ReadBigEndian(4)));
    position_ += 4;
    if (value < 0) {
      Fail(field, "negative count " + std::to_string(value));
      return -1;
    }
    return value;
  }
  // `count` strings: each an int32 length >= 1 (it counts the NUL), then that many bytes.
  void SkipStrings(std::int64_t count, const char* field) {
    for (std::int64_t i = 0; i < count && ok(); ++i) {
      const std::int64_t length = ReadCount(field);
      if (length == 0) return Fail(field, "string length 0 (it must count the NUL)");
      Skip(length, 1, field);
    }
  }
  // The walk must end exactly at the end of the bytes.
  bool Finish(std::string* error) {
    if (ok() && position_ != size_)
      Fail("", std::to_string(size_ - position_) + " bytes after the message");
    if (!ok() && error != nullptr) *error = error_;
    return ok();
  }
  bool ok() const { return error_.empty(); }

 private:
  bool Need(std::int64_t bytes, const char* field) {
    if (!ok()) return false;
    if (bytes <= size_ - position_) return true;
    Fail(field, "needs " + std::to_string(bytes) + " bytes, " + std::to_string(size_ - position_) +
                    " remain of " + std::to_string(size_));
    return false;
  }
  std::uint64_t ReadBigEndian(int bytes) const {
    std::uint64_t value = 0;
    for (int i = 0; i < bytes; ++i) value = (value << 8) | data_[position_ + i];
    return value;
  }
  void Fail(const char* field, const std::string& why) {
    if (ok()) error_ = std::string(type_) + (*field ? std::string(".") + field : "") + ": " + why;
  }

  const std::uint8_t* data_;
  std::int64_t size_;
  std::int64_t position_ = 0;
  const char* type_;
  std::string error_;
};

constexpr int kDouble = 8, kInt64 = 8, kInt32 = 4, kFloat = 4, kInt8 = 1, kBoolean = 1;

}  // namespace

template <>
bool CheckWireLayout<hapsim_lcm::device_state_t>(const void* data, int size, std::string* error) {
  using T = hapsim_lcm::device_state_t;
  WireCursor wire(data, size, T::getTypeName());
  wire.ExpectHash(T::getHash());
  wire.Skip(3, kInt64, "utime, run_id, sequence");
  wire.Skip(3 + 4 + 3 + 3, kDouble, "x_W_m, q_WD, v_W_m_s, w_W_rad_s");
  wire.Skip(1, kInt32, "buttons");
  return wire.Finish(error);
}

template <>
bool CheckWireLayout<hapsim_lcm::device_force_t>(const void* data, int size, std::string* error) {
  using T = hapsim_lcm::device_force_t;
  WireCursor wire(data, size, T::getTypeName());
  wire.ExpectHash(T::getHash());
  wire.Skip(3, kInt64, "utime, run_id, sequence");
  wire.Skip(6, kDouble, "force_W_N, torque_W_N_m");
  wire.Skip(1, kBoolean, "zeroed");
  wire.SkipStrings(1, "reason");
  return wire.Finish(error);
}

template <>
bool CheckWireLayout<hapsim_lcm::haptic_state_t>(const void* data, int size, std::string* error) {
  using T = hapsim_lcm::haptic_state_t;
  WireCursor wire(data, size, T::getTypeName());
  wire.ExpectHash(T::getHash());
  wire.Skip(4, kInt64, "utime, run_id, step, device_sequence");
  wire.Skip(1 + 3 + 4 + 3 + 3 + 3 + 3 + 3 + 3, kDouble, "device_age_s ... torque_contact_W_N_m");
  wire.Skip(1, kInt64, "model_sequence");
  wire.Skip(5, kDouble, "model_age_s ... period_error_max_s");
  wire.Skip(1, kInt64, "overruns");
  wire.Skip(1, kBoolean, "zeroed");
  wire.SkipStrings(1, "reason");
  wire.Skip(1, kDouble, "passivity_energy_J");
  return wire.Finish(error);
}

template <>
bool CheckWireLayout<hapsim_lcm::contact_model_t>(const void* data, int size, std::string* error) {
  using T = hapsim_lcm::contact_model_t;
  WireCursor wire(data, size, T::getTypeName());
  wire.ExpectHash(T::getHash());
  wire.Skip(3, kInt64, "utime, run_id, sequence");
  wire.Skip(3 + 3 + 4 + 3 + 4 + 3 + 3, kDouble, "dt_visual_s ... visual_L_W_kg_m2_s");
  wire.Skip(1, kInt32, "num_contacts");
  wire.Skip(3 + 3 + 4 * 9, kDouble, "F_c0_N ... dTc_dT");
  const std::int64_t rows = wire.ReadCount("num_rows");
  wire.Skip(2 * rows * 3, kDouble, "J_v and J_w (num_rows each)");
  wire.Skip(1, kInt32, "num_coupled_rows");
  const std::int64_t lower = wire.ReadCount("num_W_body_lower");
  wire.Skip(lower, kDouble, "W_body_lower");
  const std::int64_t contact_lower = wire.ReadCount("num_W_body_contact_lower");
  wire.Skip(contact_lower, kDouble, "W_body_contact_lower");
  wire.Skip(2 * rows, kDouble, "body_rhs, lambda_frame_N");
  const std::int64_t gaps = wire.ReadCount("num_row_gaps");
  wire.Skip(3 * gaps, kDouble, "gap_m, gap_target_m_s, surface_velocity_m_s");
  wire.Skip(1, kInt8, "rows_per_contact");
  const std::int64_t mus = wire.ReadCount("num_friction_coefficients");
  wire.Skip(mus, kDouble, "friction_coefficient");
  const std::int64_t nodes = wire.ReadCount("num_body_nodes");
  wire.Skip(nodes * 3, kDouble, "body_x_W_m");
  const std::int64_t objects = wire.ReadCount("num_objects");
  wire.Skip(objects * (3 + 4), kDouble, "object_x_W_m, object_q_WO");
  wire.Skip(1, kInt32, "num_bilateral_rows");
  return wire.Finish(error);
}

template <>
bool CheckWireLayout<hapsim_lcm::sim_frame_t>(const void* data, int size, std::string* error) {
  using T = hapsim_lcm::sim_frame_t;
  WireCursor wire(data, size, T::getTypeName());
  wire.ExpectHash(T::getHash());
  wire.Skip(3, kInt64, "utime, run_id, sequence");
  wire.Skip(1, kDouble, "t_s");
  const std::int64_t nodes = wire.ReadCount("num_nodes");
  wire.Skip(nodes * 3, kFloat, "positions_W_m");
  const std::int64_t triangles = wire.ReadCount("num_triangles");
  wire.Skip(triangles * 3, kInt32, "triangles");
  wire.Skip(3 + 4, kDouble, "x_W_m, q_WT");
  const std::int64_t contacts = wire.ReadCount("num_contacts");
  wire.Skip(contacts * (3 + 3 + 1), kDouble, "p_W_m, n_W, lambda_N");
  wire.Skip(8, kDouble, "time_coupling_s ... time_total_s");
  wire.Skip(contacts, kInt8, "contact_kind");
  const std::int64_t objects = wire.ReadCount("num_objects");
  wire.Skip(objects * (3 + 4), kDouble, "object_x_W_m, object_q_WO");
  wire.Skip(2, kInt32, "selected_object, grabbed_object");
  const std::int64_t grasped = wire.ReadCount("num_grasped");
  wire.Skip(grasped, kInt32, "grasped_nodes");
  wire.Skip(1, kInt32, "num_grasp_slipped");
  return wire.Finish(error);
}

template <>
bool CheckWireLayout<hapsim_lcm::run_info_t>(const void* data, int size, std::string* error) {
  using T = hapsim_lcm::run_info_t;
  WireCursor wire(data, size, T::getTypeName());
  wire.ExpectHash(T::getHash());
  wire.Skip(2, kInt64, "utime, run_id");
  wire.SkipStrings(3, "scene_path, scene_yaml, scene_directory");
  const std::int64_t files = wire.ReadCount("num_files");
  wire.SkipStrings(2 * files, "file_paths, file_sha256");
  wire.SkipStrings(1, "mode");
  wire.Skip(2, kDouble, "visual_rate_hz, haptic_rate_hz");
  wire.SkipStrings(1, "hapsim_version");
  return wire.Finish(error);
}

bool PeekRunId(const void* data, int size, std::int64_t* run_id) {
  if (size < 24) return false;
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  const auto read = [bytes](int offset) {
    std::uint64_t value = 0;
    for (int i = 0; i < 8; ++i) value = (value << 8) | bytes[offset + i];
    return static_cast<std::int64_t>(value);
  };
  const std::int64_t hash = read(0);
  if (hash != hapsim_lcm::device_state_t::getHash() &&
      hash != hapsim_lcm::device_force_t::getHash() &&
      hash != hapsim_lcm::haptic_state_t::getHash() &&
      hash != hapsim_lcm::contact_model_t::getHash() &&
      hash != hapsim_lcm::sim_frame_t::getHash() && hash != hapsim_lcm::run_info_t::getHash())
    return false;
  *run_id = read(16);  // after the fingerprint and utime (wire_decode.h)
  return true;
}

template <>
void SizeArraysToCounts(hapsim_lcm::contact_model_t* msg) {
  msg->J_v.resize(msg->num_rows);
  msg->J_w.resize(msg->num_rows);
  msg->W_body_lower.resize(msg->num_W_body_lower);
  msg->W_body_contact_lower.resize(msg->num_W_body_contact_lower);
  msg->body_rhs.resize(msg->num_rows);
  msg->lambda_frame_N.resize(msg->num_rows);
  msg->gap_m.resize(msg->num_row_gaps);
  msg->gap_target_m_s.resize(msg->num_row_gaps);
  msg->surface_velocity_m_s.resize(msg->num_row_gaps);
  msg->friction_coefficient.resize(msg->num_friction_coefficients);
  msg->body_x_W_m.resize(msg->num_body_nodes);
  msg->object_x_W_m.resize(msg->num_objects);
  msg->object_q_WO.resize(msg->num_objects);
}

template <>
void SizeArraysToCounts(hapsim_lcm::sim_frame_t* msg) {
  msg->positions_W_m.resize(msg->num_nodes);
  msg->triangles.resize(msg->num_triangles);
  msg->p_W_m.resize(msg->num_contacts);
  msg->n_W.resize(msg->num_contacts);
  msg->lambda_N.resize(msg->num_contacts);
  msg->contact_kind.resize(msg->num_contacts);
  msg->object_x_W_m.resize(msg->num_objects);
  msg->object_q_WO.resize(msg->num_objects);
  msg->grasped_nodes.resize(msg->num_grasped);
}

template <>
void SizeArraysToCounts(hapsim_lcm::run_info_t* msg) {
  msg->file_paths.resize(msg->num_files);
  msg->file_sha256.resize(msg->num_files);
}

}  // namespace hapsim::messages
