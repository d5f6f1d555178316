// Fuzz target: the Wavefront OBJ reader of hapsim::ReadTriangleMesh, on the input written to a
// .obj file. A mesh it accepts must be closed, oriented and enclose a volume
// (triangle_mesh_checks.h).

#include <cstddef>
#include <cstdint>

#include "core/triangle_mesh_io.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/fuzz/triangle_mesh_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hapsim;
  const std::string path = fuzz::WriteScratchFile("input.obj", data, size);
  TriangleMesh mesh;
  if (fuzz::RunReader([&] { mesh = ReadTriangleMesh(path); })) fuzz::CheckReadTriangleMesh(mesh);
  return 0;
}
