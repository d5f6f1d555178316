#pragma once
// Choices of method for the deformable body, made once per scene (DESIGN.md §2).

#include <string>

namespace hapsim::fem {

// Elastic force model. kLinear (R_e = I) is kept to show its ghost forces under rotation.
enum class ElasticityKind { kCorotational, kLinear };

// Time integrator. kExplicit (symplectic Euler) is kept to show where it blows up.
enum class IntegratorKind { kImplicitEuler, kExplicitEuler };

// Linear solver for the implicit step.
enum class SolverKind { kConjugateGradient, kCholmod };

// Preconditioner for CG. kLaggedCholesky keeps a CHOLMOD factor of an earlier system matrix and
// refactors only when CG needed more than `refactor_after_iterations` iterations with it (the
// lazy-update idea of Hecht et al. 2012): the warped stiffness changes slowly, so an old factor
// is a near-exact inverse for many steps. kBlockJacobi inverts each node's 3×3 diagonal block.
enum class PreconditionerKind { kLaggedCholesky, kBlockJacobi };

struct SolverOptions {
  SolverKind kind = SolverKind::kConjugateGradient;
  PreconditionerKind preconditioner = PreconditionerKind::kLaggedCholesky;
  double relative_tolerance = 1e-6;  // CG stops at ‖r‖ ≤ tol · ‖b‖
  int max_iterations = 1000;         // CG iteration cap
  int refactor_after_iterations = 8; // kLaggedCholesky: refactor when a solve took more
};

struct FemOptions {
  ElasticityKind elasticity = ElasticityKind::kCorotational;
  IntegratorKind integrator = IntegratorKind::kImplicitEuler;
  SolverOptions solver;
};

const char* ToString(ElasticityKind kind);
const char* ToString(IntegratorKind kind);
const char* ToString(SolverKind kind);
const char* ToString(PreconditionerKind kind);

}  // namespace hapsim::fem
