// Mesh writers: Gmsh MSH ASCII 2.2/4.1, TetGen .node/.ele, legacy VTK unstructured grid.

#include <cstdio>
#include <fstream>
#include <ostream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "fem/mesh_io.h"

namespace hapsim::fem {
namespace {

// Precondition of every writer: tet indices (corners, and a quadratic mesh's edge nodes) address
// existing nodes.
template <typename Indices>
void CheckTetIndices(const Indices& tets, Eigen::Index num_nodes) {
  HAPSIM_INVARIANT(tets.size() == 0 || (tets.minCoeff() >= 0 && tets.maxCoeff() < num_nodes));
}

void WriteXyz(std::ostream& out, const Eigen::Vector3d& v) {
  out << v[0] << ' ' << v[1] << ' ' << v[2] << '\n';
}

// Gmsh's element type: 4, the linear tet, or 11, the quadratic one (its node order is
// fem/quadratic_tet.h's: the corners, then the nodes of edges 01 12 20 30 32 31).
int GmshTetType(const TetMesh& mesh) { return mesh.is_quadratic() ? 11 : 4; }

// MSH 2.2: tags 1..N and 1..T; each tet carries 2 tags (physical 1, elementary 1).
void WriteGmsh22(const TetMesh& mesh, std::ostream& out) {
  out << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
  out << "$Nodes\n" << mesh.num_nodes() << '\n';
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    out << i + 1 << ' ';
    WriteXyz(out, mesh.rest_positions_m.col(i));
  }
  out << "$EndNodes\n$Elements\n" << mesh.num_tets() << '\n';
  for (int t = 0; t < mesh.num_tets(); ++t) {
    out << t + 1 << ' ' << GmshTetType(mesh) << " 2 1 1";
    for (int a = 0; a < mesh.nodes_per_tet(); ++a) out << ' ' << mesh.node(a, t) + 1;
    out << '\n';
  }
  out << "$EndElements\n";
}

// MSH 4.1: one volume entity (tag 1, its bounding box), one node block and one element block.
void WriteGmsh41(const TetMesh& mesh, std::ostream& out) {
  const int n = mesh.num_nodes();
  const int t_count = mesh.num_tets();
  out << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
  out << "$Entities\n0 0 0 " << (n > 0 ? 1 : 0) << '\n';
  if (n > 0) {
    const Eigen::Vector3d min_m = mesh.rest_positions_m.rowwise().minCoeff();
    const Eigen::Vector3d max_m = mesh.rest_positions_m.rowwise().maxCoeff();
    out << "1 " << min_m[0] << ' ' << min_m[1] << ' ' << min_m[2] << ' ' << max_m[0] << ' '
        << max_m[1] << ' ' << max_m[2] << " 0 0\n";
  }
  out << "$EndEntities\n";
  out << "$Nodes\n" << (n > 0 ? 1 : 0) << ' ' << n << ' ' << (n > 0 ? 1 : 0) << ' ' << n << '\n';
  if (n > 0) {
    out << "3 1 0 " << n << '\n';
    for (int i = 0; i < n; ++i) out << i + 1 << '\n';
    for (int i = 0; i < n; ++i) WriteXyz(out, mesh.rest_positions_m.col(i));
  }
  out << "$EndNodes\n";
  out << "$Elements\n"
      << (t_count > 0 ? 1 : 0) << ' ' << t_count << ' ' << (t_count > 0 ? 1 : 0) << ' ' << t_count
      << '\n';
  if (t_count > 0) {
    out << "3 1 " << GmshTetType(mesh) << ' ' << t_count << '\n';
    for (int t = 0; t < t_count; ++t) {
      out << t + 1;
      for (int a = 0; a < mesh.nodes_per_tet(); ++a) out << ' ' << mesh.node(a, t) + 1;
      out << '\n';
    }
  }
  out << "$EndElements\n";
}

}  // namespace

void WriteGmshMesh(const TetMesh& mesh, const std::string& path, int version_major) {
  if (version_major != 2 && version_major != 4)
    throw InputError(path, 0, "version",
                     "Gmsh output version must be 2 (MSH 2.2) or 4 (MSH 4.1), "
                     "got " +
                         std::to_string(version_major));
  CheckTetIndices(mesh.tets, mesh.num_nodes());
  CheckTetIndices(mesh.edge_nodes, mesh.num_nodes());
  WriteFileAtomically(path, [&](std::ostream& out) {
    if (version_major == 2) WriteGmsh22(mesh, out);
    if (version_major == 4) WriteGmsh41(mesh, out);
  });
}

void WriteTetgenMesh(const TetMesh& mesh, const std::string& basename) {
  CheckTetIndices(mesh.tets, mesh.num_nodes());
  WriteFileAtomically(basename + ".node", [&](std::ostream& out) {
    out << "# hapsim: <# of points> <dimension> <# of attributes> <boundary markers>\n";
    out << mesh.num_nodes() << " 3 0 0\n";
    for (int i = 0; i < mesh.num_nodes(); ++i) {
      out << i + 1 << ' ';
      WriteXyz(out, mesh.rest_positions_m.col(i));
    }
  });
  WriteFileAtomically(basename + ".ele", [&](std::ostream& out) {
    out << "# hapsim: <# of tetrahedra> <nodes per tetrahedron> <region attribute>\n";
    out << mesh.num_tets() << " 4 0\n";
    for (int t = 0; t < mesh.num_tets(); ++t) {
      out << t + 1;
      for (int a = 0; a < 4; ++a) out << ' ' << mesh.tets(a, t) + 1;
      out << '\n';
    }
  });
}

void WriteVtkTetMesh(const Matrix3Xd& positions_m, const Matrix4Xi& tets,
                     const std::vector<std::pair<std::string, const Matrix3Xd*>>& point_vectors,
                     const std::string& path) {
  const Eigen::Index num_nodes = positions_m.cols();
  CheckTetIndices(tets, num_nodes);
  for (const auto& [name, field] : point_vectors) {
    HAPSIM_INVARIANT(field != nullptr && field->cols() == num_nodes);
    if (name.empty() || name.find_first_of(" \t\r\n") != std::string::npos)
      throw InputError(path, 0, name, "a VTK field name must be non-empty without whitespace");
  }
  WriteFileAtomically(path, [&](std::ostream& out) {
    out << "# vtk DataFile Version 3.0\nhapsim tetrahedral mesh\nASCII\n"
        << "DATASET UNSTRUCTURED_GRID\n";
    out << "POINTS " << num_nodes << " double\n";
    for (Eigen::Index i = 0; i < num_nodes; ++i) WriteXyz(out, positions_m.col(i));
    out << "CELLS " << tets.cols() << ' ' << 5 * tets.cols() << '\n';
    for (Eigen::Index t = 0; t < tets.cols(); ++t)
      out << "4 " << tets(0, t) << ' ' << tets(1, t) << ' ' << tets(2, t) << ' ' << tets(3, t)
          << '\n';
    out << "CELL_TYPES " << tets.cols() << '\n';
    for (Eigen::Index t = 0; t < tets.cols(); ++t) out << "10\n";  // VTK_TETRA
    if (point_vectors.empty()) return;
    out << "POINT_DATA " << num_nodes << '\n';
    for (const auto& [name, field] : point_vectors) {
      out << "VECTORS " << name << " double\n";
      for (Eigen::Index i = 0; i < num_nodes; ++i) WriteXyz(out, field->col(i));
    }
  });
}

}  // namespace hapsim::fem
