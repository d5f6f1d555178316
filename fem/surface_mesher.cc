#include "fem/surface_mesher.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "fem/gmsh_library.h"

namespace hapsim::fem {
namespace {

// Tets in a volume at edge h: the volume over a regular tet's, h³/(6√2), times 0.7, which is
// what Gmsh made, a little over: a sphere r = 50 mm at 10 mm gave 2,658 tets (estimate 3,109),
// the liver at 8 mm 5,226 (estimate 5,730).
double EstimateTets(double volume_m3, double h_m) {
  return 0.7 * volume_m3 * 6.0 * std::sqrt(2.0) / (h_m * h_m * h_m);
}

void CheckOptions(const SurfaceMeshOptions& options, const std::string& label) {
  if (!(options.cell_size_m > 0.0) || !std::isfinite(options.cell_size_m))
    throw InputError(label, 0, "cell_size_m", "must be a positive length in metres");
  if (options.refine_near_m.empty()) return;
  if (!(options.refine_cell_size_m > 0.0) || options.refine_cell_size_m > options.cell_size_m)
    throw InputError(label, 0, "refine.cell_size_m", "must be in (0, cell_size_m]");
  if (!(options.refine_radius_m > 0.0) || !std::isfinite(options.refine_radius_m))
    throw InputError(label, 0, "refine.radius_m", "must be a positive length in metres");
  for (const Eigen::Vector3d& p : options.refine_near_m)
    if (!p.allFinite()) throw InputError(label, 0, "refine.near_m", "must be finite points");
}

// Connected pieces of the surface (triangles joined through shared vertices), by union–find.
int CountPieces(const TriangleMesh& surface) {
  std::vector<int> parent(static_cast<size_t>(surface.vertices_m.cols()));
  std::iota(parent.begin(), parent.end(), 0);
  const auto root = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (Eigen::Index t = 0; t < surface.triangles.cols(); ++t)
    for (int k = 1; k < 3; ++k)
      parent[root(surface.triangles(k, t))] = root(surface.triangles(0, t));
  std::vector<char> used(parent.size(), 0);
  for (Eigen::Index t = 0; t < surface.triangles.cols(); ++t) used[surface.triangles(0, t)] = 1;
  int pieces = 0;
  for (size_t v = 0; v < parent.size(); ++v)
    pieces += used[v] && root(static_cast<int>(v)) == static_cast<int>(v);
  return pieces;
}

// Gmsh's partitioner splits a closed surface into patches a map can flatten; on a surface of a
// handful of triangles (a tetrahedron's four) it splits the same patch forever. Each triangle is
// cut into four at its edges' midpoints until there are at least 256: the new vertices lie on the
// old flat facets, so the surface is the same.
TriangleMesh SubdivideSmallSurface(TriangleMesh surface) {
  constexpr Eigen::Index kEnoughTriangles = 256;
  while (surface.triangles.cols() < kEnoughTriangles) {
    std::map<std::pair<int, int>, int> midpoint;
    std::vector<Eigen::Vector3d> vertices(surface.vertices_m.cols());
    for (Eigen::Index v = 0; v < surface.vertices_m.cols(); ++v)
      vertices[v] = surface.vertices_m.col(v);
    const auto middle = [&](int a, int b) {
      const auto [it, added] =
          midpoint.emplace(std::minmax(a, b), static_cast<int>(vertices.size()));
      if (added) vertices.push_back(0.5 * (vertices[a] + vertices[b]));
      return it->second;
    };
    Matrix3Xi triangles(3, 4 * surface.triangles.cols());
    for (Eigen::Index t = 0; t < surface.triangles.cols(); ++t) {
      const int a = surface.triangles(0, t), b = surface.triangles(1, t),
                c = surface.triangles(2, t);
      const int ab = middle(a, b), bc = middle(b, c), ca = middle(c, a);
      triangles.col(4 * t) << a, ab, ca;
      triangles.col(4 * t + 1) << ab, b, bc;
      triangles.col(4 * t + 2) << ca, bc, c;
      triangles.col(4 * t + 3) << ab, bc, ca;
    }
    surface.vertices_m.resize(3, static_cast<Eigen::Index>(vertices.size()));
    for (size_t v = 0; v < vertices.size(); ++v)
      surface.vertices_m.col(static_cast<Eigen::Index>(v)) = vertices[v];
    surface.triangles = triangles;
  }
  return surface;
}

}  // namespace

std::string SurfaceMesherVersion() {
  // Bump the hapsim part when MeshClosedSurface's settings change what it makes.
  return "hapsim surface mesher 1, " + internal::GmshVersion();
}

// Gmsh over CGAL's Mesh_3, measured on a sphere and the liver surface at the same cell size
// (tests/bench/mesher_comparison.cc, docs/SCENES.md): CGAL was 1.6–3.7× faster (liver at 8 mm:
// 0.09 against 0.32 s) with 10–20 % fewer tets, but Gmsh's volume was the closer to the surface's
// (liver −1.0 % against −1.5 % at 8 mm, −0.4 against −0.7 % at 5 mm), its worst dihedral angle on
// the organ the better (12.2° against 9.4° at 8 mm), its mesh the same every run (CGAL's sliver
// perturbation is randomised), and the same library grades the size by fields and reads every
// Gmsh file version. A meshed surface is cached (config/), so its time is paid once.
TetMesh MeshClosedSurface(const TriangleMesh& surface, const SurfaceMeshOptions& options,
                          const std::string& label, const SurfaceMeshLimits& limits) {
  CheckOptions(options, label);
  const double volume_m3 = CalcSignedVolume_m3(surface);
  if (!(volume_m3 > 0.0)) throw InputError(label, 0, "surface", "encloses no volume");
  if (const int pieces = CountPieces(surface); pieces > 1)
    throw InputError(label, 0, "surface",
                     "has " + std::to_string(pieces) +
                         " separate closed pieces; give each organ its own object and file");
  double expected_tets = EstimateTets(volume_m3, options.cell_size_m);
  for (size_t i = 0; i < options.refine_near_m.size(); ++i)
    expected_tets += EstimateTets(4.0 / 3.0 * M_PI * std::pow(2.0 * options.refine_radius_m, 3),
                                  options.refine_cell_size_m);
  if (expected_tets > limits.max_tets)
    throw InputError(label, 0, "cell_size_m",
                     "would give about " + std::to_string(static_cast<long long>(expected_tets)) +
                         " tets, more than " + std::to_string(limits.max_tets) +
                         ": choose larger cells");
  const internal::GmshVolumeMesh made = internal::RunGmshInChildProcess(
      [&, subdivided = SubdivideSmallSurface(surface)] {
        return internal::MeshVolumeWithGmsh(subdivided, options);
      },
      limits.timeout_s);
  if (!made.error.empty())
    throw InputError(label, 0, "surface", "the mesher could not fill it: " + made.error);
  if (made.tet_tags.empty()) throw InputError(label, 0, "surface", "the mesher made no tets");
  return internal::MakeTetMeshFromGmsh(made, label, "surface");
}

}  // namespace hapsim::fem
