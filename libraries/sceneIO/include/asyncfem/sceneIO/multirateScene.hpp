// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/sceneIO/simulation.hpp>

namespace asyncfem {

/// The registry factory for name "multirate-uncoupled": UncoupledMultirate (the
/// compound-step comparator of the asynchronous integrator, uncoupledMultirate.hpp) with
/// regions given exactly as for "async" (explicit `regions`, or "auto" with `auto`; read by
/// parseAsyncOptions) plus:
///
/// | key | values | meaning |
/// |---|---|---|
/// | `regionSolver` | solver name, default `"cholmod"` | factorization of each A^{S_i} |
/// | `compoundSolver` | `"umfpack"` (default) \| `"eigen-lu"` | LU of the unsymmetric compound system |
///
/// The async-only keys `schur`, `method`, `recovery`, `substepContact` are rejected with
/// an error naming them.
IntegratorFactory uncoupledMultirateIntegratorFactory();

}  // namespace asyncfem
