// Fuzz target: the Gmsh MSH reader (fem::ReadGmshMesh), on the input written to a .msh file. A
// mesh it accepts must keep the promises of fem/mesh_io.h (tet_mesh_checks.h).

#include <cstddef>
#include <cstdint>

#include "fem/mesh_io.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/fuzz/tet_mesh_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hapsim;
  const std::string path = fuzz::WriteScratchFile("input.msh", data, size);
  fem::TetMesh mesh;
  if (fuzz::RunReader([&] { mesh = fem::ReadGmshMesh(path); })) fuzz::CheckReadTetMesh(mesh);
  return 0;
}
