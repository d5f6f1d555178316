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

// Preconditioner for CG. kLaggedCholesky keeps a CHOLMOD factor of an earlier system matrix (the
// lazy-update idea of Hecht et al. 2012): the warped stiffness changes slowly, so an old factor is
// a near-exact inverse for many steps. It refactors when the iterations spent beyond those of the
// first solve after the last factorisation add up to `refactor_budget_iterations`, i.e. when the
// stale factor has cost about as much as a new one. kBlockJacobi inverts each node's 3×3 block.
enum class PreconditionerKind { kLaggedCholesky, kBlockJacobi };

// Precision of the lagged Cholesky factor's triangular solves (CG itself is double). kSingle
// applies a float copy of the factor (fem/single_precision_factor.h): one apply 2.7x faster at
// 28.8k tets (2.4 against 6.5 ms: L no longer overflows the L3 cache), 1.6x at 3.6k (0.12
// against 0.20 ms; BM_FactorSolve, 2026-11-26). The float
// factor leaves a residual near CG's 1e-6 tolerance, so about one step in six needs a second
// iteration (1.4 a step against 1.25 over 200 steps from rest); net, the 28.8k step's mean is
// 13.1 against 15.4 ms, the 3.6k step's 0.83 against 1.20 (bench_fem.sh, 2026-11-26 05:42; 0.81
// against 0.87 in a run 20 minutes before: the 3.6k means are noisy), and
// block_press's frames are faster (docs/BENCHMARKS.md, issue 13). Answers agree to CG's
// tolerance: device forces within 5e-8 N RMS, the same number of refactorisations.
//
// kHalf applies a binary16 copy (fem/half_precision_factor.h): half the bytes of the float one,
// one apply 1.55 against 3.62 ms at 28.8k tets (BM_FactorSolve, bench_fem.sh of 2026-11-26
// 14:14). Its entries carry 4.9e-4 relative rounding, so even a fresh factor leaves CG ~3
// iterations a step to 1e-6 instead of 1.5: on the settled block (`fem --bench`, same run) 0.98
// against 0.85 ms at 3.6k, and at 28.8k a lower mean (11.5 against 12.4 ms, one factorisation
// instead of two) but a higher median (10.6 against 9.9 ms). It pays where the factor is stale
// anyway: on block_press_large every solve takes 3–6 iterations whatever the precision, and the
// frame median fell from 59–64 to 41–43 ms (alternating runs, 13:45; device forces within 5e-8 N
// RMS). So kSingle stays the default and a scene that presses a large body chooses kHalf
// (scenes/block_press_large.yaml).
enum class FactorPrecision { kSingle, kDouble, kHalf };

struct SolverOptions {
  SolverKind kind = SolverKind::kConjugateGradient;
  PreconditionerKind preconditioner = PreconditionerKind::kLaggedCholesky;
  double relative_tolerance = 1e-6;  // CG stops at ‖r‖ ≤ tol · ‖b‖
  int max_iterations = 1000;         // CG iteration cap
  // kLaggedCholesky: the stale factor's extra iterations allowed before a new factor, about what a
  // numeric factorisation costs in preconditioned CG iterations. Chosen when a factorisation took
  // 40–60 (236 ms vs 6 ms at 28.8k tets, 16 vs 0.27 ms at 3.6k). Since CHOLMOD runs on one thread
  // and the float factor's apply is faster (2026-11-26) it is nearer 25–30 (107 vs ~3.6 ms, 4.9
  // vs ~0.2 ms), but a budget of 25 measured no better: fem 200-step means 1.05 vs 1.12 ms at
  // 3.6k, 13.0–14.0 vs 13.5–14.3 ms at 28.8k; block_press_large's mean frame 74–79 vs 70 ms
  // (two runs each), where a fresh factor leaves 2–3 iterations a solve rather than 1.
  // Deterministic: counts iterations, not time.
  int refactor_budget_iterations = 50;
  FactorPrecision factor_precision = FactorPrecision::kSingle;  // kLaggedCholesky only
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
const char* ToString(FactorPrecision precision);  // "single" | "double" | "half"

}  // namespace hapsim::fem
