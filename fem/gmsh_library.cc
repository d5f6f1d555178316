#include "fem/gmsh_library.h"

#include <dlfcn.h>
#include <fcntl.h>
#include <gmsh.h>  // GMSH_API_VERSION only: libgmsh is loaded by the plugin
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <stdexcept>

#include "fem/mesh_text_reader.h"

namespace hapsim::fem::internal {
namespace {

// The child's answer on the pipe: the four arrays and the nodes per tet, each as its length then
// its elements (size_t, double and uint64 as the machine has them: both ends are this program),
// then the error's length and bytes.
void Append(std::string* bytes, const void* data, size_t size) {
  if (size > 0) bytes->append(static_cast<const char*>(data), size);  // data may be null at 0
}
template <typename T>
void AppendArray(std::string* bytes, const std::vector<T>& values) {
  const std::uint64_t count = values.size();
  Append(bytes, &count, sizeof count);
  Append(bytes, values.data(), count * sizeof(T));
}
std::string Encode(const GmshVolumeMesh& mesh) {
  std::string bytes;
  AppendArray(&bytes, mesh.node_tags);
  AppendArray(&bytes, mesh.coordinates_m);
  AppendArray(&bytes, mesh.tet_tags);
  AppendArray(&bytes, mesh.tet_nodes);
  AppendArray(&bytes, std::vector<std::uint64_t>{mesh.nodes_per_tet});
  AppendArray(&bytes, std::vector<char>(mesh.error.begin(), mesh.error.end()));
  return bytes;
}

// False if `bytes` ends early (the child died while writing).
template <typename T>
bool ReadArray(const std::string& bytes, size_t* at, std::vector<T>* values) {
  std::uint64_t count = 0;
  if (bytes.size() - *at < sizeof count) return false;
  std::memcpy(&count, bytes.data() + *at, sizeof count);
  *at += sizeof count;
  if (count > (bytes.size() - *at) / sizeof(T)) return false;
  values->resize(count);
  if (count > 0) std::memcpy(values->data(), bytes.data() + *at, count * sizeof(T));
  *at += count * sizeof(T);
  return true;
}
bool Decode(const std::string& bytes, GmshVolumeMesh* mesh) {
  size_t at = 0;
  std::vector<char> error;
  std::vector<std::uint64_t> nodes_per_tet;
  const bool whole =
      ReadArray(bytes, &at, &mesh->node_tags) && ReadArray(bytes, &at, &mesh->coordinates_m) &&
      ReadArray(bytes, &at, &mesh->tet_tags) && ReadArray(bytes, &at, &mesh->tet_nodes) &&
      ReadArray(bytes, &at, &nodes_per_tet) && ReadArray(bytes, &at, &error) &&
      at == bytes.size() && nodes_per_tet.size() == 1 &&
      (nodes_per_tet[0] == 4 || nodes_per_tet[0] == 10);
  if (!whole) return false;
  mesh->nodes_per_tet = nodes_per_tet[0];
  mesh->error.assign(error.begin(), error.end());
  return mesh->coordinates_m.size() == 3 * mesh->node_tags.size() &&
         mesh->tet_nodes.size() == mesh->nodes_per_tet * mesh->tet_tags.size();
}

[[noreturn]] void RunChild(int fd, const std::function<GmshVolumeMesh()>& work) {
  prctl(PR_SET_PDEATHSIG, SIGKILL);  // not left running if hapsim dies
  // A Gmsh crash ends this process as the signal's default does, for the parent to report: not in
  // a handler the parent installed (a sanitizer's, libFuzzer's) that would take it for its own.
  // Gmsh does crash: a surface the fuzzer made had it throw inside an OpenMP region (terminate).
  for (const int signal_number : {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGTRAP})
    ::signal(signal_number, SIG_DFL);
  // Gmsh's own messages are off (General.Terminal), but its linear algebra (gmm) prints warnings
  // straight to stderr, hundreds on a bad surface: the child's output goes nowhere.
  if (!std::getenv("HAPSIM_GMSH_VERBOSE")) {
    const int null_fd = open("/dev/null", O_WRONLY);
    if (null_fd >= 0) {
      dup2(null_fd, STDOUT_FILENO);
      dup2(null_fd, STDERR_FILENO);
      close(null_fd);
    }
  }
  const std::string bytes = Encode(work());
  for (size_t at = 0; at < bytes.size();) {
    const ssize_t written = write(fd, bytes.data() + at, bytes.size() - at);
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0) _exit(1);
    at += static_cast<size_t>(written);
  }
  _exit(0);  // no exit handlers or destructors of the parent's state
}

// Reads the child's answer until end of file or the deadline; false at the deadline.
bool ReadUntil(int fd, std::chrono::steady_clock::time_point deadline, std::string* bytes) {
  char buffer[1 << 16];
  for (;;) {
    const auto left = deadline - std::chrono::steady_clock::now();
    const int wait_ms = static_cast<int>(std::max<long long>(
        0, std::chrono::duration_cast<std::chrono::milliseconds>(left).count()));
    pollfd ready{fd, POLLIN, 0};
    const int polled = poll(&ready, 1, wait_ms);
    if (polled < 0 && errno == EINTR) continue;
    if (polled == 0) return false;
    const ssize_t got = read(fd, buffer, sizeof buffer);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0)
      return true;  // end of file (or an error: what came so far is judged whole or not)
    bytes->append(buffer, static_cast<size_t>(got));
  }
}

// Loads the plugin and runs `call` with it, or says why it could not be loaded. Called in the
// child process, each time: the parent never loads it, so each fork starts without it.
template <typename Call>
GmshVolumeMesh WithPlugin(const Call& call) {
  const char* given = std::getenv("HAPSIM_GMSH_PLUGIN");
  const std::string path = given && *given ? given : HAPSIM_GMSH_PLUGIN;
  GmshVolumeMesh failed;
  void* module = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (module == nullptr) {
    failed.error = std::string("cannot load Gmsh (") + dlerror() + ")";
    return failed;
  }
  using Entry = const GmshPlugin* (*)();
  const auto entry = reinterpret_cast<Entry>(dlsym(module, "HapsimGmshPlugin"));
  if (entry == nullptr) {
    failed.error = "the Gmsh plugin " + path + " has no entry point";
    return failed;
  }
  return call(*entry());
}

}  // namespace

GmshVolumeMesh MeshVolumeWithGmsh(const TriangleMesh& surface, const SurfaceMeshOptions& options) {
  return WithPlugin([&](const GmshPlugin& gmsh) { return gmsh.mesh_volume(surface, options); });
}

GmshVolumeMesh ReadTetsWithGmsh(const std::string& path) {
  return WithPlugin([&](const GmshPlugin& gmsh) { return gmsh.read_tets(path); });
}

std::string GmshVersion() { return std::string("Gmsh API ") + GMSH_API_VERSION; }

GmshVolumeMesh RunGmshInChildProcess(const std::function<GmshVolumeMesh()>& work,
                                     double timeout_s) {
  int fds[2];
  if (pipe(fds) != 0)
    throw std::runtime_error(std::string("mesher: pipe: ") + std::strerror(errno));
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    throw std::runtime_error(std::string("mesher: fork: ") + std::strerror(errno));
  }
  if (pid == 0) {
    close(fds[0]);
    RunChild(fds[1], work);
  }
  close(fds[1]);
  std::string bytes;
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(timeout_s));
  const bool finished = ReadUntil(fds[0], deadline, &bytes);
  close(fds[0]);
  if (!finished) kill(pid, SIGKILL);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  GmshVolumeMesh mesh;
  if (!finished) {
    mesh.error = "did not finish within " + std::to_string(static_cast<int>(timeout_s)) + " s";
  } else if (WIFSIGNALED(status)) {
    mesh.error = std::string("crashed (") + strsignal(WTERMSIG(status)) + ")";
  } else if (!Decode(bytes, &mesh)) {
    mesh = GmshVolumeMesh{};
    mesh.error = "its process ended without a whole answer";
  }
  return mesh;
}

TetMesh MakeTetMeshFromGmsh(const GmshVolumeMesh& made, const std::string& label,
                            const std::string& key) {
  std::vector<RawNode> nodes(made.node_tags.size());
  for (size_t i = 0; i < nodes.size(); ++i)
    nodes[i] = {static_cast<long long>(made.node_tags[i]),
                Eigen::Vector3d(made.coordinates_m[3 * i], made.coordinates_m[3 * i + 1],
                                made.coordinates_m[3 * i + 2]),
                0};
  std::vector<RawTet> tets(made.tet_tags.size());
  for (size_t e = 0; e < tets.size(); ++e) {
    const int n = static_cast<int>(made.nodes_per_tet);
    tets[e].tag = static_cast<long long>(made.tet_tags[e]);
    for (int k = 0; k < n; ++k)
      tets[e].nodes[k] = static_cast<long long>(made.tet_nodes[n * e + k]);
    tets[e].line = 0;
    tets[e].num_nodes = n;
  }
  return MakeCheckedTetMesh(nodes, label, key, tets, label, key);
}

}  // namespace hapsim::fem::internal
