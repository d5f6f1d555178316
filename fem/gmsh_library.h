#pragma once
// What hapsim asks of Gmsh's library (libgmsh-dev), for fem/surface_mesher.h and the MSH reader
// (fem/gmsh_reader.cc): a closed surface remeshed at a cell size and its volume filled, and a
// mesh file of any MSH version read. Internal. Gmsh can hang or crash on input it cannot handle,
// so the callers run these in a child process (RunGmshInChildProcess), after their own checks.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/tool_shape.h"
#include "fem/surface_mesher.h"
#include "fem/tet_mesh.h"

namespace hapsim::fem::internal {

// What Gmsh made: node tags and coordinates (x y z per node), tet tags and their 4 (or 10) node
// tags each.
// On failure `error` holds Gmsh's message and the tets are empty.
struct GmshVolumeMesh {
  std::vector<std::size_t> node_tags;
  std::vector<double> coordinates_m;
  std::vector<std::size_t> tet_tags;
  std::vector<std::size_t> tet_nodes;  // nodes_per_tet per tet (Gmsh's order)
  std::uint64_t nodes_per_tet = 4;     // 4, or 10 for second-order tets (type 11)
  std::string error;
};

// The nodes and tets Gmsh gave as a checked TetMesh (the readers' conventions, fem/mesh_io.h);
// problems are InputError(label, 0, key, ...). Precondition: no error, some tets.
TetMesh MakeTetMeshFromGmsh(const GmshVolumeMesh& made, const std::string& label,
                            const std::string& key);

// `surface` closed, outward-oriented and in one piece; `options` checked. In the child process
// only: it loads the plugin (below).
GmshVolumeMesh MeshVolumeWithGmsh(const TriangleMesh& surface, const SurfaceMeshOptions& options);

// The linear tets of a mesh file in any format Gmsh reads (MSH 1, binary 2.2 and 4.x, 4.0), as
// Gmsh's own reader gives them. Volume elements other than linear tets come back as `error`. In
// the child process only, as MeshVolumeWithGmsh.
GmshVolumeMesh ReadTetsWithGmsh(const std::string& path);

// The two above as fem/gmsh_plugin.cc implements them, in a shared module (hapsim_gmsh) loaded
// with dlopen by the first call, so that only a child process ever loads libgmsh (~0.2 s). Its
// path is the build's (HAPSIM_GMSH_PLUGIN), or $HAPSIM_GMSH_PLUGIN if set.
struct GmshPlugin {
  GmshVolumeMesh (*mesh_volume)(const TriangleMesh& surface, const SurfaceMeshOptions& options);
  GmshVolumeMesh (*read_tets)(const std::string& path);
};

// `work` (MeshVolumeWithGmsh, ReadTetsWithGmsh) in a child process (fork), its result sent back
// through a pipe: a Gmsh that hangs is killed after timeout_s, and one that crashes takes only
// the child. Either comes back as `error` ("did not finish within ...", "crashed (...)"). Throws
// std::runtime_error only when no child can be started (pipe or fork failing). The child of a
// process with threads holds only the calling one, and dlopen there could wait on a lock another
// thread held at the fork. hapsim loads scenes before it starts threads of its own (the viewer
// builds its body after creating its off-screen renderer, not yet drawing); a child that waits
// anyway is killed at the deadline like any other.
GmshVolumeMesh RunGmshInChildProcess(const std::function<GmshVolumeMesh()>& work, double timeout_s);

// "Gmsh <version of the library>".
std::string GmshVersion();

}  // namespace hapsim::fem::internal
