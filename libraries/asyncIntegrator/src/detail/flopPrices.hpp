// SPDX-License-Identifier: BSD-3-Clause
// Flop prices shared by the rent-or-buy rules of the lagged Schur factor and the quick
// set-up (docs/asynchronous-integrator.md). Private to the library.
#pragma once

namespace asyncfem::detail {

/// What a flop of a supernodal factorization, or of a solve with many right-hand sides
/// (Z's columns in blocks), costs against one of a single solve (BLAS 3 against memory-
/// bound substitutions). Measured on this project's 2-core machine, one thread, corotational
/// beam and dinosaur (benchmarkAsync --study steady --corotational): a lagged iteration (the
/// forward substitutions with A^S, one-column kernel of sparseSolver, and the single-
/// precision kept factor) runs at about 7 GFlop/s, a rebuild (Z and the factor of H^{LL*})
/// at 9.6-10 GFlop/s: 0.7. (It was 0.4 while single solves went through CHOLMOD's BLAS
/// calls at 3.2-4.8 GFlop/s; priced at 0.4 since, rebuilds cost 1.7-2x their price.)
inline constexpr double kBlockedFlopWeight = 0.7;
/// The same weight for the quick set-up's rule (Eq. Q4), whose iterations solve with the
/// whole system's factor (millions of entries: CHOLMOD's solves with OpenBLAS's kernels, at
/// the 3.2-4.8 GFlop/s measured for it): 0.4.
inline constexpr double kQuickBlockedFlopWeight = 0.4;
/// The fixed cost of one solve call (wrapping, scatter and gather, CHOLMOD's workspace) in
/// flops of a solve, which dominates the small A^S solves of a forward substitution.
inline constexpr double kSolveCallFlops = 1e5;

}  // namespace asyncfem::detail
