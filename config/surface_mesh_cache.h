#pragma once
// A deformable object's `mesh: {surface: FILE, cell_size_m: h}` (issue 26): the closed surface
// read (core/triangle_mesh_io.h) and filled with tets (fem/surface_mesher.h), with the result
// cached so that a scene loads fast the second time.
//
// The cache is keyed by the SHA-256 of the surface file's (core/content_hash.h) with the meshing
// options, the transform and the mesher's version, so an edited surface, another cell size or
// another Gmsh meshes again. Entries are Gmsh 4.1 files (written to a temporary name and renamed: a
// crash leaves no half-written entry), in $HAPSIM_MESH_CACHE if set, else
// $XDG_CACHE_HOME/hapsim/meshes, else
// ~/.cache/hapsim/meshes. A cache that cannot be written is skipped with a note on stderr; an entry
// that cannot be read is meshed again and rewritten.

#include <string>

#include "core/mesh_transform.h"
#include "fem/surface_mesher.h"
#include "fem/tet_mesh.h"

namespace hapsim::config {

struct SurfaceMeshResult {
  fem::TetMesh mesh;
  bool from_cache = false;
  std::string cache_file;  // the entry read or written; empty when there is no cache
  double surface_volume_m3 = 0.0;  // what the surface encloses, placed (to judge the mesh by)
};

// Throws InputError naming the surface file (unreadable, open, misoriented: its line) or what the
// mesher refused (fem::MeshClosedSurface).
// `transform` places the surface (its units, rotation, translation) before it is meshed.
SurfaceMeshResult MeshSurfaceFile(const std::string& surface_file,
                                  const fem::SurfaceMeshOptions& options,
                                  const MeshTransform& transform = {});

// The folder the cache uses now (see above), or empty if no home is known.
std::string SurfaceMeshCacheFolder();

}  // namespace hapsim::config
