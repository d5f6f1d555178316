#pragma once
// The Gmsh calls of fem/surface_mesher.h, in this process: the surface remeshed at the cell size
// and its volume filled. Internal: fem::MeshClosedSurface checks the input first and runs this in
// a child process, because Gmsh can hang or crash on a surface it cannot handle.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/tool_shape.h"
#include "fem/surface_mesher.h"

namespace hapsim::fem::internal {

// What Gmsh made: node tags and coordinates (x y z per node), tet tags and their 4 node tags each.
// On failure `error` holds Gmsh's message and the tets are empty.
struct GmshVolumeMesh {
  std::vector<std::size_t> node_tags;
  std::vector<double> coordinates_m;
  std::vector<std::size_t> tet_tags;
  std::vector<std::size_t> tet_nodes;
  std::string error;
};

// `surface` closed, outward-oriented and in one piece; `options` checked.
GmshVolumeMesh MeshVolumeWithGmsh(const TriangleMesh& surface, const SurfaceMeshOptions& options);

// MeshVolumeWithGmsh in a child process (fork), its result sent back through a pipe: a Gmsh that
// hangs is killed after timeout_s, and one that crashes takes only the child. Either comes back
// as `error` ("did not finish within ...", "crashed: ..."). Throws std::runtime_error only when
// no child can be started (pipe or fork failing).
GmshVolumeMesh MeshVolumeInChildProcess(const TriangleMesh& surface,
                                        const SurfaceMeshOptions& options, double timeout_s);

// "Gmsh <version of the library>".
std::string GmshVersion();

}  // namespace hapsim::fem::internal
