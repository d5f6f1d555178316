// A block for the flat-punch experiment (scripts/bench/punch_rim.py), meshed by Gmsh so that
// its tets are finest along the punch's rim: the rim is a circle embedded in the block's top face
// (nodes on it, no face crossing it), and the cell size grows linearly with the distance from that
// circle, from --rim-cell-size-m on it to --cell-size-m at --grading-distance-m and beyond (Gmsh's
// Distance and Threshold fields). The pressure under a rigid flat punch is singular at the rim,
// p ~ (a² − r²)^(−1/2) (Johnson, Contact Mechanics, §3.7), and a mesh graded towards the rim is
// the textbook remedy; the lattices of scenes/flat_punch.yaml can only be fine around a point.
// With --from-disk the size grows from the whole disk inside the circle instead: the sphere's
// contact zone (scripts/bench/hertz_disk.py), fine all across it.
// With --quarter-point-fraction q the mesh is written quadratic instead, its edge nodes at the
// midpoints except on the edges that leave a node of the rim, whose nodes sit q of the way along
// (fem/quarter_point_nodes.h: q ≈ ¼ makes the elements at the rim hold the √ρ field there).
// Not a test: a bench program. Writes linear tets (MSH 4.1; the scene's `element: p2` adds the
// mid-edge nodes on straight edges) or, with a fraction, quadratic ones, through a temporary file
// renamed at the end, and prints "tets N" and "rim_nodes M" (the nodes on the rim circle: its
// polygon's sides). Usage: punch_block_mesh --help.
#include <CLI/CLI.hpp>
#include <gmsh.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "fem/gmsh_session.h"
#include "fem/mesh_io.h"
#include "fem/quarter_point_nodes.h"
#include "fem/tet_mesh.h"

namespace {

struct Options {
  std::array<double, 3> min_m{-0.03, -0.03, 0.0};
  std::array<double, 3> max_m{0.03, 0.03, 0.03};
  double rim_radius_m = 0.003;
  double rim_cell_size_m = 0.0;
  double cell_size_m = 0.0;
  double grading_distance_m = 0.02;
  bool from_disk = false;  // grade from the whole disk inside the rim, not from the rim alone
  double quarter_point_fraction = 0.0;  // 0: linear tets; else quadratic, as the header says
  std::string out;
};

// The block with the rim circle (centred over the top face, at its height) fragmented into its
// top face; what the size grows from: with --from-disk the disk inside the rim after the fragment
// (its faces), without it the curves that bound the disk (the rim, whether one curve or split).
gmsh::vectorpair MakeBlockWithRim(const Options& o) {
  const int block = gmsh::model::occ::addBox(o.min_m[0], o.min_m[1], o.min_m[2],
                                             o.max_m[0] - o.min_m[0], o.max_m[1] - o.min_m[1],
                                             o.max_m[2] - o.min_m[2]);
  const int circle = gmsh::model::occ::addCircle(0.5 * (o.min_m[0] + o.max_m[0]),
                                                 0.5 * (o.min_m[1] + o.max_m[1]), o.max_m[2],
                                                 o.rim_radius_m);
  const int disk = gmsh::model::occ::addPlaneSurface({gmsh::model::occ::addCurveLoop({circle})});
  gmsh::vectorpair fragments;
  std::vector<gmsh::vectorpair> origin;  // per input entity, what it became
  gmsh::model::occ::fragment({{3, block}}, {{2, disk}}, fragments, origin);
  gmsh::model::occ::synchronize();
  if (o.from_disk) return origin.at(1);
  gmsh::vectorpair rim;
  gmsh::model::getBoundary(origin.at(1), rim, /*combined=*/false, /*oriented=*/false);
  return rim;
}

// h(d) = rim + (cell − rim) min(d / D, 1), d the distance from the rim (or the disk).
void GradeTowardsRim(const Options& o, const gmsh::vectorpair& rim) {
  namespace field = gmsh::model::mesh::field;
  std::vector<double> tags;
  for (const auto& [dim, tag] : rim) tags.push_back(tag);
  field::add("Distance", 1);
  field::setNumbers(1, o.from_disk ? "SurfacesList" : "CurvesList", tags);
  field::setNumber(1, "NumPointsPerCurve", 400);
  field::add("Threshold", 2);
  field::setNumber(2, "InField", 1);
  field::setNumber(2, "SizeMin", o.rim_cell_size_m);
  field::setNumber(2, "SizeMax", o.cell_size_m);
  field::setNumber(2, "DistMin", 0.0);
  field::setNumber(2, "DistMax", o.grading_distance_m);
  field::setAsBackgroundMesh(2);
  // The field alone sets the size (not the corners' defaults, nor the curvature of the circle).
  gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 0);
  gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
  gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
  gmsh::option::setNumber("Mesh.Optimize", 1);
}

// The nodes of the linear `mesh` on the rim circle: in the top face, at the rim's radius from its
// centre (Gmsh puts them on the circle to round-off).
std::vector<bool> FindRimNodes(const Options& o, const hapsim::fem::TetMesh& mesh) {
  const double cx = 0.5 * (o.min_m[0] + o.max_m[0]), cy = 0.5 * (o.min_m[1] + o.max_m[1]);
  const double tolerance_m = 1e-6 * o.rim_radius_m;
  std::vector<bool> on_rim(static_cast<std::size_t>(mesh.num_nodes()), false);
  for (int n = 0; n < mesh.num_nodes(); ++n) {
    const auto x = mesh.rest_positions_m.col(n);
    on_rim[static_cast<std::size_t>(n)] =
        std::abs(x.z() - o.max_m[2]) < tolerance_m &&
        std::abs(std::hypot(x.x() - cx, x.y() - cy) - o.rim_radius_m) < tolerance_m;
  }
  return on_rim;
}

struct Meshed {
  std::size_t num_tets = 0;
  long num_rim_nodes = 0;
};

// Counts the rim's nodes in the linear mesh in `temporary` and, with a quarter-point fraction,
// rewrites it as quadratic with the rim's edges' nodes moved (the header).
long FinishMesh(const Options& o, const std::string& temporary) {
  hapsim::fem::TetMesh mesh = hapsim::fem::ReadTetMesh(temporary);
  std::vector<bool> on_rim = FindRimNodes(o, mesh);
  const long num_rim_nodes = std::count(on_rim.begin(), on_rim.end(), true);
  if (!o.from_disk && num_rim_nodes < 3)  // the rim is what the mesh is graded to: it must be there
    throw std::runtime_error("fewer than 3 nodes found on the rim circle");
  if (o.quarter_point_fraction == 0.0) return num_rim_nodes;
  mesh = hapsim::fem::MakeQuadraticMesh(mesh);
  on_rim.resize(static_cast<std::size_t>(mesh.num_nodes()), false);  // edge nodes: not on it
  hapsim::fem::MoveEdgeNodesToQuarterPoints(on_rim, o.quarter_point_fraction, &mesh);
  if (auto problem = hapsim::fem::FindRestMeshProblem(mesh))
    throw std::runtime_error("the quarter-point mesh is unusable: " + *problem);
  hapsim::fem::WriteGmshMesh(mesh, temporary, 4);
  return num_rim_nodes;
}

// Meshes and writes `temporary` (Gmsh), then reads it back to count the rim's nodes and, with a
// quarter-point fraction, rewrites it quadratic (FinishMesh).
Meshed MeshInto(const Options& o, const std::string& temporary) {
  hapsim::fem::internal::GmshSession session;
  gmsh::model::add("punch_block");
  const gmsh::vectorpair rim = MakeBlockWithRim(o);
  if (rim.empty())
    throw std::runtime_error(std::string("Gmsh kept no ") + (o.from_disk ? "face" : "curve") +
                             " of the rim's disk in the top face");
  GradeTowardsRim(o, rim);
  gmsh::model::mesh::generate(3);
  std::vector<std::size_t> tets, nodes;
  gmsh::model::mesh::getElementsByType(4, tets, nodes);
  gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
  gmsh::write(temporary);  // Gmsh picks the format by the extension
  return {tets.size(), FinishMesh(o, temporary)};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "A block whose top face holds a flat punch's rim circle, meshed by Gmsh with linear tets "
      "finest along the rim (the flat-punch experiment, scripts/bench/punch_rim.py), or with "
      "--from-disk finest across the disk inside it (a sphere's contact, hertz_disk.py)."};
  Options o;
  app.add_option("--min-m", o.min_m, "Block's lower corner, m")->capture_default_str();
  app.add_option("--max-m", o.max_m, "Block's upper corner, m (the rim at its top)")
      ->capture_default_str();
  app.add_option("--rim-radius-m", o.rim_radius_m, "Rim circle's radius, m, centred over the top")
      ->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--rim-cell-size-m", o.rim_cell_size_m,
                 "Tet edge length on the rim (on the disk with --from-disk), m")
      ->required()->check(CLI::PositiveNumber);
  app.add_option("--cell-size-m", o.cell_size_m, "Tet edge length far from the rim, m")
      ->required()->check(CLI::PositiveNumber);
  app.add_option("--grading-distance-m", o.grading_distance_m,
                 "Distance from the rim (or disk) over which the edge length grows to "
                 "--cell-size-m, m")
      ->capture_default_str()->check(CLI::PositiveNumber);
  app.add_flag("--from-disk", o.from_disk,
               "Grade from the whole disk inside the rim (a sphere's contact zone), not the rim");
  app.add_option("--quarter-point-fraction", o.quarter_point_fraction,
                 "Write quadratic tets whose edges leaving the rim have their nodes this fraction "
                 "of the way along (1/4 < q <= 1/2; about 1/4 holds the root-of-distance field at "
                 "the rim); 0 writes linear tets")
      ->capture_default_str();
  app.add_option("--out", o.out, "Output mesh, FILE.msh")->required();
  CLI11_PARSE(app, argc, argv);
  for (int a = 0; a < 3; ++a)
    if (!(o.max_m[a] > o.min_m[a])) {
      std::fprintf(stderr, "punch_block_mesh: --max-m must exceed --min-m on every axis\n");
      return 2;
    }
  const double half_width_m = 0.5 * std::min(o.max_m[0] - o.min_m[0], o.max_m[1] - o.min_m[1]);
  if (o.rim_radius_m >= half_width_m) {
    std::fprintf(stderr, "punch_block_mesh: the rim (radius %g m) must fit in the top face\n",
                 o.rim_radius_m);
    return 2;
  }
  if (o.rim_cell_size_m > o.cell_size_m) {
    std::fprintf(stderr, "punch_block_mesh: --rim-cell-size-m must not exceed --cell-size-m\n");
    return 2;
  }
  if (o.quarter_point_fraction != 0.0 &&
      !(o.quarter_point_fraction > 0.25 && o.quarter_point_fraction <= 0.5)) {
    std::fprintf(stderr, "punch_block_mesh: --quarter-point-fraction must be 0 or in (1/4, 1/2] "
                         "(at 1/4 exactly the rim's elements are singular at their corner)\n");
    return 2;
  }
  if (o.quarter_point_fraction != 0.0 && o.from_disk) {
    std::fprintf(stderr, "punch_block_mesh: --quarter-point-fraction is for the rim, not "
                         "--from-disk\n");
    return 2;
  }
  if (std::filesystem::path(o.out).extension() != ".msh") {
    std::fprintf(stderr, "punch_block_mesh: --out must end in .msh\n");
    return 2;
  }
  const std::string temporary = o.out + ".tmp.msh";
  try {
    const Meshed meshed = MeshInto(o, temporary);
    std::filesystem::rename(temporary, o.out);
    std::printf("tets %zu\nrim_nodes %ld\n", meshed.num_tets, meshed.num_rim_nodes);
    return 0;
  } catch (const std::string& gmsh_error) {  // Gmsh 4.8's API throws its message as a string
    std::fprintf(stderr, "punch_block_mesh: Gmsh: %s\n", gmsh_error.c_str());
  } catch (const std::exception& error) {
    std::fprintf(stderr, "punch_block_mesh: %s\n", error.what());
  }
  std::error_code ignored;  // nothing half-written
  std::filesystem::remove(temporary, ignored);
  return 1;
}
