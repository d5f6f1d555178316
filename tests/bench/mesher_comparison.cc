// Gmsh (fem/surface_mesher.h, what hapsim uses) against CGAL's Mesh_3 on the same closed
// surfaces, at the same target cell size (issue 26 item 1): meshing time (median of 3), tets,
// the extreme dihedral angles, and the volume against the one the surface encloses. Not a test:
// configure with -DHAPSIM_BUILD_MESHER_COMPARISON=ON (and the benchmarks on, as by default), then
// run `build/tests/mesher_comparison` from the repository root (it reads scenes/meshes/liver.obj);
// it prints a Markdown table (docs/SCENES.md).
//
// CGAL's criteria, as its manual's polyhedral-domain examples set them, scaled to the cell size
// h: facet angle ≥ 25°, facet size and cell size h, facet distance h/10, radius–edge ratio ≤ 3,
// then its default sliver perturbation and exudation.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polyhedral_mesh_domain_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/make_mesh_3.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/shape_mesh.h"
#include "core/triangle_mesh_io.h"
#include "fem/surface_mesher.h"
#include "fem/tet_mesh.h"

namespace hapsim {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Surface = CGAL::Surface_mesh<Kernel::Point_3>;
using Domain = CGAL::Polyhedral_mesh_domain_3<Surface, Kernel>;
using Triangulation = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using Complex = CGAL::Mesh_complex_3_in_triangulation_3<Triangulation>;
using Criteria = CGAL::Mesh_criteria_3<Triangulation>;

fem::TetMesh MeshWithCgal(const TriangleMesh& surface, double h_m) {
  Surface polyhedron;
  std::vector<Surface::Vertex_index> vertex;
  for (Eigen::Index i = 0; i < surface.vertices_m.cols(); ++i)
    vertex.push_back(polyhedron.add_vertex(Kernel::Point_3(
        surface.vertices_m(0, i), surface.vertices_m(1, i), surface.vertices_m(2, i))));
  for (Eigen::Index t = 0; t < surface.triangles.cols(); ++t)
    polyhedron.add_face(vertex[surface.triangles(0, t)], vertex[surface.triangles(1, t)],
                        vertex[surface.triangles(2, t)]);
  const Domain domain(polyhedron);
  namespace P = CGAL::parameters;
  const Criteria criteria(P::facet_angle = 25, P::facet_size = h_m, P::facet_distance = h_m / 10,
                          P::cell_radius_edge_ratio = 3, P::cell_size = h_m);
  const Complex complex = CGAL::make_mesh_3<Complex>(domain, criteria);
  // Vertices of the cells in the complex, compacted; cells oriented positively.
  std::map<Triangulation::Vertex_handle, int> index;
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector4i> tets;
  for (auto c = complex.cells_in_complex_begin(); c != complex.cells_in_complex_end(); ++c) {
    Eigen::Vector4i tet;
    for (int k = 0; k < 4; ++k) {
      const auto v = c->vertex(k);
      auto [it, inserted] = index.emplace(v, static_cast<int>(points.size()));
      if (inserted) {
        const auto p = complex.triangulation().point(c, k).point();
        points.emplace_back(p.x(), p.y(), p.z());
      }
      tet[k] = it->second;
    }
    tets.push_back(tet);
  }
  fem::TetMesh mesh;
  mesh.rest_positions_m.resize(3, static_cast<Eigen::Index>(points.size()));
  for (size_t i = 0; i < points.size(); ++i)
    mesh.rest_positions_m.col(static_cast<Eigen::Index>(i)) = points[i];
  mesh.tets.resize(4, static_cast<Eigen::Index>(tets.size()));
  for (size_t e = 0; e < tets.size(); ++e) {
    Eigen::Vector4i tet = tets[e];
    if (fem::CalcSignedVolume(mesh.rest_positions_m, tet) < 0.0) std::swap(tet[2], tet[3]);
    mesh.tets.col(static_cast<Eigen::Index>(e)) = tet;
  }
  return mesh;
}

void Compare(const std::string& name, const TriangleMesh& surface, double h_m) {
  const double surface_volume_m3 = CalcSignedVolume_m3(surface);
  const std::vector<std::pair<std::string, std::function<fem::TetMesh()>>> meshers = {
      {"Gmsh",
       [&] {
         return fem::MeshClosedSurface(surface, {h_m, {}, 0.0, 0.0}, name);
       }},
      {"CGAL", [&] { return MeshWithCgal(surface, h_m); }}};
  for (const auto& [mesher, mesh_it] : meshers) {
    std::vector<double> seconds;
    fem::TetMesh mesh;
    for (int run = 0; run < 3; ++run) {
      const auto start = std::chrono::steady_clock::now();
      mesh = mesh_it();
      seconds.push_back(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    std::sort(seconds.begin(), seconds.end());
    const fem::TetMeshQuality q = fem::CalcTetMeshQuality(mesh);
    std::printf("| %s, h %.1f mm | %s | %.3f s | %d | %ld | %.1f° – %.1f° | %+.2f %% |\n",
                name.c_str(), 1e3 * h_m, mesher.c_str(), seconds[1], q.num_tets,
                static_cast<long>(mesh.rest_positions_m.cols()), q.min_dihedral_deg,
                q.max_dihedral_deg, 100.0 * (q.volume_m3 / surface_volume_m3 - 1.0));
  }
}

}  // namespace
}  // namespace hapsim

int main() {
  using namespace hapsim;
  ToolShape sphere;
  sphere.kind = ToolShape::Kind::kSphere;
  sphere.radius_m = 0.05;
  const TriangleMesh sphere_surface = MakeShapeMesh(sphere, 64);
  const TriangleMesh liver = ReadTriangleMesh("scenes/meshes/liver.obj");
  std::printf("| surface | mesher | time | tets | nodes | dihedral angles | volume vs surface |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (double h_m : {0.01, 0.005}) Compare("sphere r 50 mm (3,968 triangles)", sphere_surface, h_m);
  for (double h_m : {0.008, 0.005}) Compare("liver (9,024 triangles)", liver, h_m);
  return 0;
}
