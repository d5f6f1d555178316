#pragma once
// W = J A⁻¹ Jᵀ, the exact contact compliance (docs/CONTACT.md), from a supernodal CHOLMOD factor
// A = Pᵀ L Lᵀ P in double precision, solving only where the contacts' dofs reach.
//
// Why not CHOLMOD's sparse solve (cholmod_spsolve, as before). It solves the columns of P Jᵀ four
// at a time, each four over the whole factor, with narrow matrix products that spend more on
// packing than on arithmetic. Here every column is solved at once, and only on the supernodes
// that can hold a nonzero: a column of P Jᵀ is nonzero at its contact's dofs, L⁻¹ keeps it zero
// off their elimination-tree paths to the root, and the backward solve is wanted only at those
// dofs, whose rows depend only on their paths' supernodes (a needed supernode's ancestors are
// needed too). So both sweeps run over the union of those paths, with the right-hand sides stored
// for its rows alone, and each supernode's work is one BLAS-3 product or triangular solve over
// all the columns (dgemm, dtrsm; OpenBLAS, as CHOLMOD's own kernels).
//
//   forward:  Y ← L⁻¹ P Jᵀ,   backward: Y ← L⁻ᵀ Y = P A⁻¹ Jᵀ,   W = J (Pᵀ Y) at the touched dofs.
//
// Measured (docs/BENCHMARKS.md, 2026-11-29, AMD EPYC VM): the compliance of block_press's frames
// (up to 218 contacts) 13.0 → 4.4 ms median, of the quadratic liver's (12.8 mm cells, up to 367)
// 103 → 35 ms; block_press's device forces the same to 1e-9 N. The same sweeps through Eigen's
// products (SSE2 in this build) gained half as much.
//
// The rounding is that of any double-precision triangular solve;
// tests/fem/contact_compliance_test.cc checks the result against a dense factorisation of A.

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "fem/supernodal_layout.h"

namespace hapsim::fem {

// layout: the factor's structure (SupernodalLayout::Assign); L_values: its entries (CHOLMOD's
// factor x, double), in that layout. J: rows × layout.size(), column-major. Returns the dense
// symmetric rows × rows matrix J A⁻¹ Jᵀ (zero if J has no entries).
Eigen::MatrixXd CalcInverseQuadraticForm(const SupernodalLayout& layout, const double* L_values,
                                         const Eigen::SparseMatrix<double>& J);

}  // namespace hapsim::fem
