#include "fem/linear_solver.h"

#include "fem/cg_solver.h"
#include "fem/cholmod_solver.h"

namespace hapsim::fem {

std::unique_ptr<LinearSolver> MakeLinearSolver(const SolverOptions& options) {
  if (options.kind == SolverKind::kCholmod) return std::make_unique<CholmodSolver>();
  return std::make_unique<ConjugateGradientSolver>(options);
}

}  // namespace hapsim::fem
