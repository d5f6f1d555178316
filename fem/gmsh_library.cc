#include "fem/gmsh_library.h"

#include <fcntl.h>
#include <gmsh.h>
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

// Gmsh is a library with one global model: each meshing initialises it, builds, reads the result
// and finalises it again, also when something throws. Its messages go nowhere (General.Terminal
// 0); its errors are exceptions (the API's AbortOnError = 2) whose text we take from its logger.
class GmshSession {
 public:
  GmshSession() {
    gmsh::initialize(0, nullptr, /*readConfigFiles=*/false);
    gmsh::option::setNumber("General.Terminal", std::getenv("HAPSIM_GMSH_VERBOSE") ? 1 : 0);
    gmsh::option::setNumber("General.NumThreads", 1);  // one core, and the same mesh every time
  }
  ~GmshSession() { gmsh::finalize(); }
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

  static std::string LastError() {
    std::string error;
    gmsh::logger::getLastError(error);
    return error.empty() ? "Gmsh gave no reason" : error;
  }
};

// The surface as one discrete Gmsh surface: nodes 1..N, triangles 1..T.
void AddDiscreteSurface(const TriangleMesh& surface) {
  const int tag = gmsh::model::addDiscreteEntity(2);
  std::vector<std::size_t> node_tags(static_cast<size_t>(surface.vertices_m.cols()));
  std::iota(node_tags.begin(), node_tags.end(), 1);
  const std::vector<double> coordinates(surface.vertices_m.data(),
                                        surface.vertices_m.data() + surface.vertices_m.size());
  gmsh::model::mesh::addNodes(2, tag, node_tags, coordinates);
  std::vector<std::size_t> triangle_tags(static_cast<size_t>(surface.triangles.cols()));
  std::iota(triangle_tags.begin(), triangle_tags.end(), 1);
  std::vector<std::size_t> triangle_nodes;
  triangle_nodes.reserve(3 * triangle_tags.size());
  for (Eigen::Index t = 0; t < surface.triangles.cols(); ++t)
    for (int k = 0; k < 3; ++k)
      triangle_nodes.push_back(static_cast<std::size_t>(surface.triangles(k, t)) + 1);
  constexpr int kGmshTriangle = 2;
  gmsh::model::mesh::addElementsByType(tag, kGmshTriangle, triangle_tags, triangle_nodes);
}

// Cell size: uniform, or graded towards the refine points (Distance + Threshold fields).
void SetCellSize(const SurfaceMeshOptions& options) {
  if (options.refine_near_m.empty()) {
    gmsh::option::setNumber("Mesh.MeshSizeMin", options.cell_size_m);
    gmsh::option::setNumber("Mesh.MeshSizeMax", options.cell_size_m);
    return;
  }
  std::vector<std::size_t> point_tags;
  for (const Eigen::Vector3d& p : options.refine_near_m)
    point_tags.push_back(static_cast<std::size_t>(gmsh::model::geo::addPoint(p.x(), p.y(), p.z())));
  gmsh::model::geo::synchronize();
  const int distance = gmsh::model::mesh::field::add("Distance");
  std::vector<double> points(point_tags.begin(), point_tags.end());
  gmsh::model::mesh::field::setNumbers(distance, "PointsList", points);
  const int threshold = gmsh::model::mesh::field::add("Threshold");
  gmsh::model::mesh::field::setNumber(threshold, "InField", distance);
  gmsh::model::mesh::field::setNumber(threshold, "SizeMin", options.refine_cell_size_m);
  gmsh::model::mesh::field::setNumber(threshold, "SizeMax", options.cell_size_m);
  gmsh::model::mesh::field::setNumber(threshold, "DistMin", options.refine_radius_m);
  gmsh::model::mesh::field::setNumber(threshold, "DistMax", 2.0 * options.refine_radius_m);
  gmsh::model::mesh::field::setAsBackgroundMesh(threshold);
  // The field alone decides the size (not the surface's own triangles, nor its curvature).
  gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 0);
  gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
  gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
}

// The child's answer on the pipe: the four arrays, each as its length then its elements (size_t
// and double as the machine has them: both ends are this program), then the error's length and
// bytes.
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
  const bool whole =
      ReadArray(bytes, &at, &mesh->node_tags) && ReadArray(bytes, &at, &mesh->coordinates_m) &&
      ReadArray(bytes, &at, &mesh->tet_tags) && ReadArray(bytes, &at, &mesh->tet_nodes) &&
      ReadArray(bytes, &at, &error) && at == bytes.size();
  mesh->error.assign(error.begin(), error.end());
  return whole && mesh->coordinates_m.size() == 3 * mesh->node_tags.size() &&
         mesh->tet_nodes.size() == 4 * mesh->tet_tags.size();
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

}  // namespace

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

GmshVolumeMesh MeshVolumeWithGmsh(const TriangleMesh& surface, const SurfaceMeshOptions& options) {
  GmshSession session;
  GmshVolumeMesh result;
  try {
    gmsh::model::add("surface");
    AddDiscreteSurface(surface);
    // Patches split at 40° creases, each reparametrisable by one map, so that the surface can be
    // remeshed at the cell size with its new nodes on the given triangles.
    gmsh::model::mesh::classifySurfaces(40.0 * M_PI / 180.0, /*boundary=*/true,
                                        /*forReparametrization=*/true);
    gmsh::model::mesh::createGeometry();
    gmsh::vectorpair patches;
    gmsh::model::getEntities(patches, 2);
    std::vector<int> patch_tags;
    for (const auto& [dim, tag] : patches) patch_tags.push_back(tag);
    gmsh::model::geo::addVolume({gmsh::model::geo::addSurfaceLoop(patch_tags)});
    gmsh::model::geo::synchronize();
    SetCellSize(options);
    gmsh::model::mesh::generate(3);
    std::vector<double> parametric;
    gmsh::model::mesh::getNodes(result.node_tags, result.coordinates_m, parametric, -1, -1,
                                /*includeBoundary=*/false, /*returnParametricCoord=*/false);
    constexpr int kGmshTet = 4;
    gmsh::model::mesh::getElementsByType(kGmshTet, result.tet_tags, result.tet_nodes);
  } catch (...) {
    result = GmshVolumeMesh{};
    result.error = GmshSession::LastError();
  }
  return result;
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
    tets[e].tag = static_cast<long long>(made.tet_tags[e]);
    for (int k = 0; k < 4; ++k)
      tets[e].nodes[k] = static_cast<long long>(made.tet_nodes[4 * e + k]);
    tets[e].line = 0;
  }
  return MakeCheckedTetMesh(nodes, label, key, tets, label, key);
}

GmshVolumeMesh ReadTetsWithGmsh(const std::string& path) {
  GmshSession session;
  GmshVolumeMesh result;
  try {
    gmsh::open(path);
    std::vector<int> volume_types;
    gmsh::model::mesh::getElementTypes(volume_types, 3);
    constexpr int kGmshTet = 4;
    for (int type : volume_types)
      if (type != kGmshTet) {
        std::string name;
        int dim = 0, order = 0, num_nodes = 0, num_primary = 0;
        std::vector<double> local;
        gmsh::model::mesh::getElementProperties(type, name, dim, order, num_nodes, local,
                                                num_primary);
        result.error = "it holds " + name + " elements (Gmsh type " + std::to_string(type) +
                       "); hapsim takes linear tetrahedra (type 4) only";
        return result;
      }
    std::vector<double> parametric;
    gmsh::model::mesh::getNodes(result.node_tags, result.coordinates_m, parametric, -1, -1,
                                /*includeBoundary=*/false, /*returnParametricCoord=*/false);
    gmsh::model::mesh::getElementsByType(kGmshTet, result.tet_tags, result.tet_nodes);
  } catch (...) {
    result = GmshVolumeMesh{};
    result.error = GmshSession::LastError();
  }
  return result;
}

}  // namespace hapsim::fem::internal
