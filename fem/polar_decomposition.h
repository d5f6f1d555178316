#pragma once
// Rotation part of a 3×3 deformation gradient, robust to inverted and flat elements.
//
// Returns the rotation R ∈ SO(3) that maximises tr(Rᵀ F), i.e. R = U diag(1, 1, det(U Vᵀ)) Vᵀ for
// F = U Σ Vᵀ: the polar rotation when det F > 0, and otherwise the rotation with the reflection
// moved into the smallest singular value (Irving, Teran & Fedkiw 2004), so that an inverted
// element is pushed back through zero volume instead of being reflected (DESIGN.md §2).
//
// Fast path: scaled Newton iteration X ← (γX + γ⁻¹X⁻ᵀ)/2, γ = |det X|^(−1/3) (Higham 1986),
// quadratically convergent for det F > 0. Elements that are inverted, nearly flat, or slow to
// converge fall back to a 3×3 SVD.

#include <Eigen/Core>

namespace hapsim::fem {

Eigen::Matrix3d CalcRotationOfDeformation(const Eigen::Matrix3d& F);

// R[i] = CalcRotationOfDeformation(F[i]) for 0 ≤ i < count, for many elements at once: the same
// iteration runs on kPolarBatchLanes elements side by side (structure of arrays, vectorised by
// the compiler), which hides the latencies of its chain of dependent steps. Results agree with
// the scalar function to round-off (≤ 1e-15 measured; up to ~5e-13 where the two land on either
// side of a convergence test), and each is independent of the other elements of its block, bit
// for bit, and of whether the SSE2 or the AVX2 copy runs (neither uses FMA; a build with -mfma
// or -march=native would round differently). Elements off the fast
// path (inverted, nearly flat, not finite, not converged) are handed to
// CalcRotationOfDeformation. R may equal F (in place); otherwise the two ranges must not overlap.
// No allocation.
void CalcRotationsOfDeformation(const Eigen::Matrix3d* F, int count, Eigen::Matrix3d* R);

// Elements per block of CalcRotationsOfDeformation: four AVX2 or eight SSE2 vectors, enough
// independent chains to hide the latencies (8 lanes: 22 instead of 19 ns per element with AVX2).
// A partial block costs as much as a full one, so callers gathering F's in chunks should use a
// multiple of it, and for a handful of elements the scalar function is cheaper.
inline constexpr int kPolarBatchLanes = 16;

}  // namespace hapsim::fem
