#include "fem/fem_options.h"

namespace hapsim::fem {

const char* ToString(ElasticityKind kind) {
  return kind == ElasticityKind::kCorotational ? "corotational" : "linear";
}
const char* ToString(IntegratorKind kind) {
  return kind == IntegratorKind::kImplicitEuler ? "implicit" : "explicit";
}
const char* ToString(SolverKind kind) {
  return kind == SolverKind::kConjugateGradient ? "cg" : "cholmod";
}

const char* ToString(PreconditionerKind kind) {
  return kind == PreconditionerKind::kLaggedCholesky ? "lagged_cholesky" : "block_jacobi";
}

const char* ToString(FactorPrecision precision) {
  switch (precision) {
    case FactorPrecision::kSingle:
      return "single";
    case FactorPrecision::kDouble:
      return "double";
    case FactorPrecision::kHalf:
      return "half";
  }
  return "?";
}

}  // namespace hapsim::fem
