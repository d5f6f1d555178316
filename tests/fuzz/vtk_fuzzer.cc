// Fuzz target: the legacy VTK reader (fem::ReadVtkMesh), ASCII and binary. A mesh it accepts
// must keep the promises of fem/mesh_io.h.

#include <cstddef>
#include <cstdint>
#include <string>

#include "fem/mesh_io.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/fuzz/tet_mesh_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hapsim;
  const std::string path = fuzz::WriteScratchFile("input.vtk", data, size);
  fem::TetMesh mesh;
  if (fuzz::RunReader([&] { mesh = fem::ReadVtkMesh(path); })) fuzz::CheckReadTetMesh(mesh);
  return 0;
}
