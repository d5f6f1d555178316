#pragma once
// One use of Gmsh's library (libgmsh-dev), whose model is global: initialised without the user's
// configuration files and on one thread (the same mesh every time), finalised when the session
// ends, also when something throws. Its messages go nowhere unless HAPSIM_GMSH_VERBOSE is set
// (General.Terminal); its errors are exceptions (the API's AbortOnError = 2), whose text
// LastError takes from its logger. For the code that links libgmsh itself: the hapsim_gmsh plugin
// (fem/gmsh_plugin.cc) and the bench's tests/bench/punch_block_mesh.cc; hapsim does not.
#include <gmsh.h>

#include <cstdlib>
#include <string>

namespace hapsim::fem::internal {

class GmshSession {
 public:
  GmshSession() {
    gmsh::initialize(0, nullptr, /*readConfigFiles=*/false);
    gmsh::option::setNumber("General.Terminal", std::getenv("HAPSIM_GMSH_VERBOSE") ? 1 : 0);
    gmsh::option::setNumber("General.NumThreads", 1);  // one core, and the same mesh every time
  }
  ~GmshSession() { gmsh::finalize(); }
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

  static std::string LastError() {
    std::string error;
    gmsh::logger::getLastError(error);
    return error.empty() ? "Gmsh gave no reason" : error;
  }
};

}  // namespace hapsim::fem::internal
