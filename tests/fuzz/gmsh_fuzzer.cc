// Fuzz target: the Gmsh MSH reader (fem::ReadGmshMesh), on the input written to a .msh file. A
// mesh it accepts must keep the promises of fem/mesh_io.h (tet_mesh_checks.h).
//
// As a libFuzzer program (HAPSIM_LIBFUZZER) it leaves out the files that ReadGmshMesh hands to
// Gmsh's own reader (MSH 1, 4.0, binary): that reader runs in a forked child, which inherits
// libFuzzer's malloc limit, and Gmsh allocates by the counts a file declares (a 306-byte binary
// file asked for over 512 MB, untouched and harmless outside the fuzzer, a "finding" inside it).
// hapsim's own parser is what this target is for; the child's protocol and its crash and hang
// handling are tested in tests/fem/mesh_io_test.cc and tests/fem/surface_mesher_test.cc, and the
// normal build's ctest runs every seed here, library formats included.

#include <cstddef>
#include <cstdint>
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>

#include "fem/mesh_io.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/fuzz/tet_mesh_checks.h"

#ifdef HAPSIM_LIBFUZZER
namespace {

// Whether ReadGmshMesh would pass the file to Gmsh's reader: it opens with $NOD or $NOE, or its
// $MeshFormat line declares version 4.0 or the binary file type. (A file this misjudges is only
// fuzzed less, or meets the child: neither hides a bug of the parser.)
bool GoesToGmshLibrary(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), std::min<std::size_t>(size, 64));
  if (text.rfind("$NOD", 0) == 0 || text.rfind("$NOE", 0) == 0) return true;
  const std::size_t line = text.find('\n');
  if (text.rfind("$MeshFormat", 0) != 0 || line == std::string::npos) return false;
  double version = 0.0;
  int file_type = 0;
  if (std::sscanf(text.c_str() + line + 1, "%lf %d", &version, &file_type) != 2) return false;
  return version == 4.0 || file_type == 1;
}

}  // namespace
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hapsim;
#ifdef HAPSIM_LIBFUZZER
  if (GoesToGmshLibrary(data, size)) return 0;
#endif
  const std::string path = fuzz::WriteScratchFile("input.msh", data, size);
  fem::TetMesh mesh;
  if (fuzz::RunReader([&] { mesh = fem::ReadGmshMesh(path); })) fuzz::CheckReadTetMesh(mesh);
  return 0;
}
