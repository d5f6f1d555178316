// The Gmsh calls of fem/gmsh_library.h, built as a plugin (hapsim_gmsh, a shared module) that
// only the child process of RunGmshInChildProcess loads: libgmsh and the OpenCASCADE libraries it
// pulls in take ~0.2 s to load, which every hapsim process (the 1 kHz haptic one included) paid
// at start-up while they were linked in (hapsim --help: 0.21 → 0.43 s).
#include <gmsh.h>

#include <cmath>
#include <numeric>

#include "fem/gmsh_library.h"
#include "fem/gmsh_session.h"

namespace hapsim::fem::internal {
namespace {

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

GmshVolumeMesh MeshVolume(const TriangleMesh& surface, const SurfaceMeshOptions& options) {
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
    result.error = "Gmsh: " + GmshSession::LastError() + " (does the surface cross itself?)";
  }
  return result;
}

GmshVolumeMesh ReadTets(const std::string& path) {
  GmshSession session;
  GmshVolumeMesh result;
  try {
    gmsh::open(path);
    std::vector<int> volume_types;
    gmsh::model::mesh::getElementTypes(volume_types, 3);
    constexpr int kGmshTet = 4, kGmshTet10 = 11;
    int tet_type = kGmshTet;
    for (int type : volume_types)
      if (type == kGmshTet10 && volume_types.size() == 1) {
        tet_type = kGmshTet10;
        result.nodes_per_tet = 10;
      } else if (type != kGmshTet) {
        std::string name;
        int dim = 0, order = 0, num_nodes = 0, num_primary = 0;
        std::vector<double> local;
        gmsh::model::mesh::getElementProperties(type, name, dim, order, num_nodes, local,
                                                num_primary);
        result.error = "it holds " + name + " elements (Gmsh type " + std::to_string(type) +
                       "); hapsim takes tetrahedra of 4 nodes (type 4) or of 10 (type 11), "
                       "not both";
        return result;
      }
    std::vector<double> parametric;
    gmsh::model::mesh::getNodes(result.node_tags, result.coordinates_m, parametric, -1, -1,
                                /*includeBoundary=*/false, /*returnParametricCoord=*/false);
    gmsh::model::mesh::getElementsByType(tet_type, result.tet_tags, result.tet_nodes);
  } catch (...) {
    result = GmshVolumeMesh{};
    result.error = "Gmsh: " + GmshSession::LastError();
  }
  return result;
}

}  // namespace
}  // namespace hapsim::fem::internal

extern "C" const hapsim::fem::internal::GmshPlugin* HapsimGmshPlugin() {
  static const hapsim::fem::internal::GmshPlugin plugin{&hapsim::fem::internal::MeshVolume,
                                                        &hapsim::fem::internal::ReadTets};
  return &plugin;
}
