#include "core/atomic_file.h"

#include <filesystem>
#include <fstream>
#include <iomanip>

#include "core/error.h"

namespace hapsim {

void WriteFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  const std::string tmp_path = path + ".tmp";
  std::error_code ec;
  {
    std::ofstream out(tmp_path, std::ios::out | std::ios::trunc);
    if (!out) throw InputError(path, 0, "", "cannot open '" + tmp_path + "' for writing");
    out << std::setprecision(kRoundTripDigits);
    try {
      write(out);
    } catch (...) {
      out.close();
      std::filesystem::remove(tmp_path, ec);
      throw;
    }
    out.close();
    if (out.fail()) {
      std::filesystem::remove(tmp_path, ec);
      throw InputError(path, 0, "", "writing '" + tmp_path + "' failed (disk full?)");
    }
  }
  std::filesystem::rename(tmp_path, path, ec);
  if (ec) {
    std::filesystem::remove(tmp_path, ec);
    throw InputError(path, 0, "", "cannot rename '" + tmp_path + "' to it: " + ec.message());
  }
}

void CreateOutputDirectory(const std::string& dir, const std::string& key) {
  if (dir.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError(dir, 0, key, "cannot create the output folder: " + ec.message());
}

}  // namespace hapsim
