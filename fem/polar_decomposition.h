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

}  // namespace hapsim::fem
