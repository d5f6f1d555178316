#pragma once
// Tetrahedral mesh files: readers for Gmsh MSH (every version: ASCII 2.x and 4.1 here, line by
// line; MSH 1, 4.0 and binary 2.x / 4.x by Gmsh's own reader), TetGen (.node + .ele) and legacy
// VTK unstructured grids (ASCII and binary),
// writers for those and for legacy VTK (ParaView). Units are taken as they stand: coordinates in
// files are read and written as metres.
//
// Every reader is strict: malformed input throws hapsim::InputError naming the file, the 1-based
// line where the problem was found (0 when the file cannot be opened), and, where it helps, the
// section or field as key (e.g. "$Nodes", "node count"). Problems found at end of file are
// reported at the file's last line, with the message naming the line the section started on.
//
// What every reader returns (the conventions callers may rely on):
//   - Only tetrahedra are kept: linear 4-node ones, or (Gmsh type 11) quadratic 10-node ones,
//     whose edge nodes go to TetMesh::edge_nodes (a file may not mix the two). Points, lines and
//     surface elements are skipped; other volume elements (hexahedra, prisms, pyramids, tets of
//     order 3 and up) throw, since silently dropping them would leave holes in the body.
//   - Node indices are compact 0..N-1 and cover only the nodes used by some tet (edge nodes
//     too), in the order in which those nodes appear in the file's node section (file
//     tags/indices are not kept).
//   - Every tet is positively oriented (CalcSignedVolume > 0). A file whose tets are all
//     negatively oriented (another generator's convention) is flipped tet by tet (indices 2 and 3
//     swapped). Mixed orientations throw at the first tet of the minority orientation (ties count
//     the negative ones as inverted); a degenerate tet (|CalcTetQuality| <= kDegenerateTetQuality)
//     throws at its line. So FindRestMeshProblem(result) is always nullopt.
//
// Writers write `path + ".tmp"` and rename it over `path` on success, so a reader never sees a
// half-written file. They write doubles with 17 significant digits: read(write(mesh)) is exact.

#include <string>
#include <utility>
#include <vector>

#include "core/eigen_types.h"
#include "fem/tet_mesh.h"

namespace hapsim::fem {

// Reads a Gmsh MSH file of any version, detected from its first section. ASCII 2.x (2.0–2.2) and
// 4.1 are parsed here, with errors at their line; unknown sections ($PhysicalNames, $Entities,
// $NodeData, ...) are skipped. MSH 1 ($NOD / $ELM), 4.0 and binary files are read by Gmsh's own
// reader (libgmsh) in a child process, so a file that crashes or hangs it ends in an error, which
// names the file at line 0. Throws InputError: file missing/unreadable (line 0); a first section
// that is neither $MeshFormat nor $NOD, or another version (3.x); counts that disagree with the
// entries; premature end of file;
// non-numeric tokens; NaN/Inf coordinates; duplicate node tags; an element naming a missing node
// tag; unsupported volume elements; no tetrahedra; degenerate or inverted tets.
TetMesh ReadGmshMesh(const std::string& path);

// Reads a TetGen mesh: `node_path` is the .node file, the .ele file, or the basename without
// either extension; the companion file is found by swapping/appending the extension.
// Node numbering starts at 0 or 1 (the first index in .node tells) and must be consecutive.
// Attribute and boundary-marker columns are read and discarded; '#' starts a comment; blank lines
// are ignored. Throws InputError for the same classes of problem as ReadGmshMesh, plus a
// dimension other than 3 and 10-node (-o2) tets, with the file being the .node or .ele file at
// fault.
TetMesh ReadTetgenMesh(const std::string& node_path);

// Reads a legacy VTK file (fem/vtk_reader.cc): DATASET UNSTRUCTURED_GRID, ASCII or BINARY
// (big-endian), the classic cell layout (file versions up to 4.2) or 5.1's OFFSETS and
// CONNECTIVITY. Tetrahedra (cell type 10) are kept; points, lines and surface cells (types 1-9,
// 21-23) skipped; every other type refused. Point and cell data are ignored. Errors name the
// section as key and, in ASCII, the line; a node's or tet's problem found after reading (a
// missing point, a degenerate tet) is at line 0 in BINARY data and 5.1's arrays.
TetMesh ReadVtkMesh(const std::string& path);

// Reads a mesh by extension (case-insensitive): .msh -> ReadGmshMesh, .node/.ele ->
// ReadTetgenMesh, .vtk -> ReadVtkMesh. Throws InputError (line 0) for any other extension, else
// what the reader throws.
TetMesh ReadTetMesh(const std::string& path);

// Writes `mesh` as Gmsh MSH ASCII, version 2.2 (version_major 2) or 4.1 (version_major 4), with
// node tags 1..N and element tags 1..T, all tets in one volume entity (tag 1); a quadratic mesh's
// as Gmsh's 10-node tets (type 11), edge nodes included.
// Throws InputError if version_major is neither 2 nor 4 or the file cannot be written.
// Precondition: mesh indices are in range (checked, aborts otherwise).
void WriteGmshMesh(const TetMesh& mesh, const std::string& path, int version_major);

// Writes `basename`.node and `basename`.ele (1-based, no attributes or markers), tets in the
// mesh's own (positive) orientation; TetGen's -r reorients tets itself on reading.
// Throws InputError if a file cannot be written. Precondition as WriteGmshMesh.
void WriteTetgenMesh(const TetMesh& mesh, const std::string& basename);

// Writes a legacy VTK ASCII (version 3.0) UNSTRUCTURED_GRID: points `positions_m`
// (3 x num_nodes, m), cells `tets` (4 x num_tets, VTK_TETRA = 10), and one VECTORS point-data
// field per entry of `point_vectors` (name -> 3 x num_nodes matrix, e.g. "displacement_m").
// Throws InputError if a field name is empty or contains whitespace (key = the name) or if the
// file cannot be written. Preconditions (checked, abort otherwise): tet indices in range, every
// field non-null with num_nodes columns.
void WriteVtkTetMesh(const Matrix3Xd& positions_m, const Matrix4Xi& tets,
                     const std::vector<std::pair<std::string, const Matrix3Xd*>>& point_vectors,
                     const std::string& path);

}  // namespace hapsim::fem
