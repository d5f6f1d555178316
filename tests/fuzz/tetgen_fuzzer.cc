// Fuzz target: the TetGen reader (fem::ReadTetgenMesh). One input holds both files: the .node
// text, a line `--- ele ---`, then the .ele text (no separator: all of it is the .node file and
// the .ele file is empty). A mesh it accepts must keep the promises of fem/mesh_io.h.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>

#include "fem/mesh_io.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/fuzz/tet_mesh_checks.h"

namespace {
constexpr std::string_view kSeparator = "\n--- ele ---\n";
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hapsim;
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  const std::size_t at = input.find(kSeparator);
  const std::size_t node_size = at == std::string_view::npos ? size : at + 1;  // keeps the '\n'
  const std::size_t ele_start = at == std::string_view::npos ? size : at + kSeparator.size();
  fuzz::WriteScratchFile("input.node", data, node_size);
  fuzz::WriteScratchFile("input.ele", data + ele_start, size - ele_start);
  const std::string basename = fuzz::ScratchDir() + "/input";
  fem::TetMesh mesh;
  if (fuzz::RunReader([&] { mesh = fem::ReadTetgenMesh(basename); })) fuzz::CheckReadTetMesh(mesh);
  return 0;
}
