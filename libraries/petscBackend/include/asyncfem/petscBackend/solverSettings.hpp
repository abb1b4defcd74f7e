// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <string>

namespace asyncfem {

/// The linear solver of the distributed systems (all symmetric positive definite once
/// the fixed DOFs are removed: M + h D + h^2 K, M + h/2 D + h^2/4 K, M).
enum class PetscSolverKind {
  /// Conjugate gradients preconditioned by PETSc's smoothed-aggregation algebraic
  /// multigrid (PCGAMG) with the six rigid-body modes as near null space.
  cgGamg,
  /// Conjugate gradients preconditioned by hypre's BoomerAMG (classical AMG).
  cgHypre,
  /// Direct: MUMPS's distributed Cholesky factorization (KSPPREONLY + PCCHOLESKY).
  mumps,
};

/// "cg-gamg", "cg-hypre" or "mumps".
std::string toString(PetscSolverKind kind);
/// Inverse of toString(); throws asyncfem::ValidationError listing the accepted names.
PetscSolverKind parsePetscSolverKind(const std::string& name);

/// How the distributed systems are solved. kind sets the KSP and PC types; the fields
/// below set the iteration controls; then PETSc's options are applied on top
/// (KSPSetFromOptions), so "-ksp_type", "-pc_type", "-pc_gamg_*", "-ksp_monitor", ...
/// in options or on the command line (PetscRuntime) override everything here. The
/// trapezoidal rule's mass solve reads the same options with the prefix "mass_"
/// ("-mass_pc_type jacobi").
struct PetscSolverSettings {
  PetscSolverKind kind = PetscSolverKind::cgGamg;
  /// Iterative kinds: stop when |b - A x|_2 <= relativeTolerance * |b|_2 (the
  /// unpreconditioned residual, so the bound means the same for every preconditioner).
  double relativeTolerance = 1e-8;
  /// Iterative kinds: also stop when |b - A x|_2 <= absoluteTolerance (force units).
  double absoluteTolerance = 0.0;
  /// Iterative kinds: a solve that needs more iterations fails (NumericalError).
  int maxIterations = 10000;
  /// More PETSc options ("-pc_gamg_threshold 0.02 -ksp_monitor"), seen by this
  /// simulation's solvers only (a private options database: these, then PETSc's global
  /// options, i.e. the command line, on top).
  std::string options;
};

}  // namespace asyncfem
