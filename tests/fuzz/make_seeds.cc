// Writes the generated part of the fuzz seed corpora (tests/fuzz/corpus/): the LCM messages and
// logs, taken from the logs of two real runs and cut down, and the meshes that hapsim's own
// writers produce. The text seeds (scenes, hand-written meshes) are committed as they are. Not
// part of the build; regenerate with
//
//   cmake --build build-fuzzcheck --target fuzz_make_seeds
//   hapsim run scenes/block_press.yaml --duration 0.1 --log linear.lcm            (in a netns)
//   hapsim run scenes/block_press.yaml --mode lcp --duration 0.6 --log lcp.lcm
//   hapsim run scenes/peg_in_hole.yaml --mode penalty --duration 0.1 --log penalty.lcm
//   build-fuzzcheck/tests/fuzz/fuzz_make_seeds linear.lcm lcp.lcm penalty.lcm tests/fuzz/corpus
//
// (Any build folder will do for fuzz_make_seeds.) contact_model/world_objects is the penalty
// run's first CONTACT_MODEL, which carries the frame's world (five objects' poses;
// docs/HAPTIC_MODES.md).
//
// Small on purpose: libFuzzer mutates small inputs faster, and the largest seed sets the input
// size it explores.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "fem/lattice_mesher.h"
#include "fem/mesh_io.h"
#include "messages/adapters.h"
#include "messages/channels.h"
#include "messages/lcm_log_reader.h"
#include "messages/wire_decode.h"

namespace {

using namespace hapsim;
namespace fs = std::filesystem;

std::string out_dir;

void WriteBytes(const std::string& target, const std::string& name, const std::string& bytes) {
  fs::create_directories(out_dir + "/" + target);
  const std::string path = out_dir + "/" + target + "/" + name;
  std::ofstream(path, std::ios::binary) << bytes;
  std::printf("%-60s %6zu bytes\n", path.c_str(), bytes.size());
}

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

template <typename T>
std::string Encode(const T& msg) {
  std::string bytes(static_cast<size_t>(msg.getEncodedSize()), '\0');
  if (msg.encode(bytes.data(), 0, static_cast<int>(bytes.size())) != static_cast<int>(bytes.size()))
    throw std::runtime_error(std::string("cannot encode ") + T::getTypeName());
  return bytes;
}

template <typename T>
void WriteMessage(const std::string& target, const std::string& name, const T& msg) {
  WriteBytes(target, name, Encode(msg));
}

struct Event {
  std::string channel;
  std::string data;
  std::int64_t timestamp_us;
};

std::vector<Event> ReadEvents(const std::string& path) {
  std::vector<Event> events;
  messages::LcmLogReader log(path);
  messages::LcmLogEvent event;
  while (log.Next(&event))
    events.push_back(
        {event.channel, std::string(event.data.begin(), event.data.end()), event.timestamp_us});
  return events;
}

template <typename T>
std::vector<T> Messages(const std::vector<Event>& events, const std::string& channel) {
  std::vector<T> found;
  for (const Event& event : events) {
    if (event.channel != channel) continue;
    T msg;
    std::string error;
    if (!messages::Decode(event.data.data(), static_cast<int>(event.data.size()), &msg, &error))
      throw std::runtime_error(error);
    found.push_back(msg);
  }
  if (found.empty()) throw std::runtime_error("no " + channel + " in the log");
  return found;
}

// LCM's event log format (messages/lcm_log_reader.h), big-endian.
void AppendBigEndian(std::uint64_t value, int bytes, std::string* out) {
  for (int i = bytes - 1; i >= 0; --i) out->push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}
void AppendEvent(std::int64_t number, std::int64_t timestamp_us, const std::string& channel,
                 const std::string& data, std::string* log) {
  AppendBigEndian(0xEDA1DA01u, 4, log);
  AppendBigEndian(static_cast<std::uint64_t>(number), 8, log);
  AppendBigEndian(static_cast<std::uint64_t>(timestamp_us), 8, log);
  AppendBigEndian(channel.size(), 4, log);
  AppendBigEndian(data.size(), 4, log);
  *log += channel;
  *log += data;
}

// Rows `first` of an lcp contact model, the first `coupled` of them coupled (the leading block of
// W_body) and the rest from its uncoupled ones (their own blocks). Normal rows only.
hapsim_lcm::contact_model_t SomeRows(hapsim_lcm::contact_model_t msg, int coupled, int uncoupled) {
  if (msg.rows_per_contact != 1 || msg.num_coupled_rows < coupled ||
      msg.num_rows - msg.num_coupled_rows < uncoupled)
    throw std::runtime_error("SomeRows: the model has too few rows of a kind");
  const auto pick = [&](auto* rows) {
    auto picked = *rows;
    picked.resize(coupled);
    picked.insert(picked.end(), rows->begin() + msg.num_coupled_rows,
                  rows->begin() + msg.num_coupled_rows + uncoupled);
    *rows = picked;
  };
  pick(&msg.J_v);
  pick(&msg.J_w);
  pick(&msg.body_rhs);
  pick(&msg.lambda_frame_N);
  if (msg.num_row_gaps > 0) {
    pick(&msg.gap_m);
    pick(&msg.gap_target_m_s);
    pick(&msg.surface_velocity_m_s);
  }
  msg.num_rows = coupled + uncoupled;
  msg.num_row_gaps = msg.num_row_gaps > 0 ? msg.num_rows : 0;
  msg.num_coupled_rows = coupled;
  msg.num_W_body_lower = coupled * (coupled + 1) / 2;
  msg.W_body_lower.resize(msg.num_W_body_lower);
  msg.num_W_body_contact_lower = uncoupled;
  msg.W_body_contact_lower.resize(uncoupled);
  msg.num_friction_coefficients = 0;
  msg.friction_coefficient.clear();
  return msg;
}

// A frame of a tetrahedron with one contact, in place of the block's surface (~100 kB).
hapsim_lcm::sim_frame_t TinyFrame(hapsim_lcm::sim_frame_t msg) {
  msg.num_nodes = 4;
  msg.positions_W_m = {{0, 0, 0}, {0.01f, 0, 0}, {0, 0.01f, 0}, {0, 0, 0.01f}};
  msg.num_triangles = 4;
  msg.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  msg.num_contacts = 1;
  msg.p_W_m = {{0.002, 0.002, 0.0}};
  msg.n_W = {{0, 0, -1}};
  msg.lambda_N = {0.5};
  msg.contact_kind = {0};
  return msg;
}

void WriteMessageSeeds(const std::vector<Event>& linear, const std::vector<Event>& lcp,
                       const std::vector<Event>& penalty) {
  // DEVICE_STATE: the first, one mid-run, a NaN position (the safety layer's case: it must pass
  // the adapter), a quaternion 1e-3 off unit (rejected).
  const auto states = Messages<hapsim_lcm::device_state_t>(linear, messages::kDeviceStateChannel);
  WriteMessage("device_state", "first", states.front());
  WriteMessage("device_state", "mid_run", states[states.size() / 2]);
  hapsim_lcm::device_state_t state = states.back();
  state.x_W_m[1] = std::numeric_limits<double>::quiet_NaN();
  WriteMessage("device_state", "nan_position", state);
  state = states.back();
  state.q_WD[0] *= 1.001;
  WriteMessage("device_state", "quaternion_off_unit", state);

  const auto forces = Messages<hapsim_lcm::device_force_t>(linear, messages::kDeviceForceChannel);
  WriteMessage("device_force", "last", forces.back());
  hapsim_lcm::device_force_t zeroed = forces.back();
  zeroed.zeroed = 1;
  zeroed.reason = "device state stale";
  zeroed.force_W_N[0] = zeroed.force_W_N[1] = zeroed.force_W_N[2] = 0.0;
  WriteMessage("device_force", "zeroed", zeroed);

  const auto haptic = Messages<hapsim_lcm::haptic_state_t>(lcp, messages::kHapticStateChannel);
  WriteMessage("haptic_state", "first", haptic.front());
  WriteMessage("haptic_state", "last", haptic.back());

  const auto linear_models =
      Messages<hapsim_lcm::contact_model_t>(linear, messages::kContactModelChannel);
  WriteMessage("contact_model", "linear", linear_models.back());
  const auto lcp_models =
      Messages<hapsim_lcm::contact_model_t>(lcp, messages::kContactModelChannel);
  const auto with_rows = std::find_if(lcp_models.rbegin(), lcp_models.rend(), [](const auto& m) {
    return m.num_coupled_rows >= 3 && m.num_rows - m.num_coupled_rows >= 2;
  });
  if (with_rows == lcp_models.rend())
    throw std::runtime_error("no lcp model with 3 coupled rows and 2 uncoupled");
  WriteMessage("contact_model", "lcp_3_rows", SomeRows(*with_rows, 3, 0));
  WriteMessage("contact_model", "lcp_1_row", SomeRows(*with_rows, 1, 0));
  WriteMessage("contact_model", "lcp_2_coupled_2_uncoupled", SomeRows(*with_rows, 2, 2));
  // Friction rows (issue 13): the three rows read as one contact's normal, t1, t2, μ 0.5.
  hapsim_lcm::contact_model_t friction = SomeRows(*with_rows, 3, 0);
  friction.rows_per_contact = 3;
  friction.num_friction_coefficients = 1;
  friction.friction_coefficient = {0.5};
  WriteMessage("contact_model", "lcp_friction_1_contact", friction);
  const auto world = Messages<hapsim_lcm::contact_model_t>(penalty, messages::kContactModelChannel);
  const auto with_world =
      std::find_if(world.begin(), world.end(), [](const auto& m) { return m.num_objects > 0; });
  if (with_world == world.end()) throw std::runtime_error("no penalty model with a world");
  WriteMessage("contact_model", "world_objects", *with_world);

  const auto frames = Messages<hapsim_lcm::sim_frame_t>(lcp, messages::kSimFrameChannel);
  WriteMessage("sim_frame", "tiny", TinyFrame(frames.back()));

  const auto infos = Messages<hapsim_lcm::run_info_t>(linear, messages::kRunInfoChannel);
  hapsim_lcm::run_info_t info = infos.front();
  WriteMessage("run_info", "block_press", info);
  // A scene that reads a file: the path the run_info target's scratch folder does not hold.
  info.scene_yaml =
      "name: from_file\ntime: {dt_s: 0.01, num_steps: 1}\nbody:\n  mesh: {file: body.msh}\n"
      "  material: {youngs_modulus_Pa: 1000, poisson_ratio: 0.3, density_kg_m3: 1000}\n";
  info.scene_directory = "/nonexistent";
  info.num_files = 1;
  info.file_paths = {"/nonexistent/body.msh"};
  info.file_sha256 = {std::string(64, '0')};
  WriteMessage("run_info", "with_file", info);
}

// Small logs: the first events of the linear run (SIM_FRAME cut down), then one with a second
// run's events interleaved (run id changed), as lcm-logger records two runs.
void WriteLogSeeds(const std::vector<Event>& linear, const std::vector<Event>& lcp) {
  std::string one_run;
  std::int64_t number = 0;
  int per_channel[6] = {};
  const char* channels[6] = {messages::kRunInfoChannel,      messages::kDeviceStateChannel,
                             messages::kDeviceForceChannel,  messages::kHapticStateChannel,
                             messages::kContactModelChannel, messages::kSimFrameChannel};
  for (const Event& event : linear) {
    const int c = static_cast<int>(std::find(channels, channels + 6, event.channel) - channels);
    if (c == 6 || per_channel[c]++ >= 2) continue;
    std::string data = event.data;
    if (event.channel == messages::kSimFrameChannel) {
      hapsim_lcm::sim_frame_t frame;
      messages::Decode(data.data(), static_cast<int>(data.size()), &frame, nullptr);
      data = Encode(TinyFrame(frame));
    }
    AppendEvent(number++, event.timestamp_us, event.channel, data, &one_run);
  }
  WriteBytes("lcm_log", "one_run.lcm", one_run);

  std::string two_runs;
  number = 0;
  int kept = 0;
  for (const Event& event : lcp) {
    if (event.channel != messages::kDeviceStateChannel &&
        event.channel != messages::kHapticStateChannel)
      continue;
    if (kept++ >= 6) break;
    std::string other = event.data;
    other[23] = static_cast<char>(other[23] ^ 0x5a);  // the run id's last byte (wire_decode.h)
    AppendEvent(number++, event.timestamp_us, event.channel, event.data, &two_runs);
    AppendEvent(number++, event.timestamp_us + 1, event.channel, other, &two_runs);
  }
  WriteBytes("lcm_log", "two_runs.lcm", two_runs);
}

// The writers' output for a 2 x 1 x 1 lattice (12 nodes, 10 tets).
void WriteMeshSeeds() {
  const fem::TetMesh mesh = fem::MakeBoxTetMesh(
      Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.02, 0.01, 0.01), Eigen::Vector3i(2, 1, 1));
  const std::string scratch = fs::temp_directory_path() / "hapsim_make_seeds";
  fs::create_directories(scratch);
  fem::WriteGmshMesh(mesh, scratch + "/box.msh", 2);
  WriteBytes("gmsh", "box_v22.msh", ReadBytes(scratch + "/box.msh"));
  fem::WriteGmshMesh(mesh, scratch + "/box.msh", 4);
  WriteBytes("gmsh", "box_v41.msh", ReadBytes(scratch + "/box.msh"));
  fem::WriteTetgenMesh(mesh, scratch + "/box");
  // tetgen_fuzzer.cc's format: .node, the separator line, .ele.
  WriteBytes("tetgen", "box.tet",
             ReadBytes(scratch + "/box.node") + "--- ele ---\n" + ReadBytes(scratch + "/box.ele"));
  fs::remove_all(scratch);

  // Binary STL of a tetrahedron (84 + 50 n bytes), outward.
  const float v[4][3] = {{0, 0, 0}, {0.01f, 0, 0}, {0, 0.01f, 0}, {0, 0, 0.01f}};
  const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::string stl(80, ' ');
  stl.replace(0, 19, "binary tetrahedron ");
  const std::uint32_t n = 4;
  stl.append(reinterpret_cast<const char*>(&n), 4);  // little-endian on this (x86) host
  for (const auto& face : faces) {
    const float normal[3] = {0, 0, 0};  // ignored by the reader
    stl.append(reinterpret_cast<const char*>(normal), 12);
    for (int k = 0; k < 3; ++k) stl.append(reinterpret_cast<const char*>(v[face[k]]), 12);
    stl.append(2, '\0');
  }
  WriteBytes("stl", "tetrahedron_binary.stl", stl);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s LINEAR_RUN.lcm LCP_RUN.lcm PENALTY_RUN.lcm CORPUS_DIR\n",
                 argv[0]);
    return 2;
  }
  out_dir = argv[4];
  try {
    const std::vector<Event> linear = ReadEvents(argv[1]);
    const std::vector<Event> lcp = ReadEvents(argv[2]);
    WriteMessageSeeds(linear, lcp, ReadEvents(argv[3]));
    WriteLogSeeds(linear, lcp);
    WriteMeshSeeds();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_make_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
