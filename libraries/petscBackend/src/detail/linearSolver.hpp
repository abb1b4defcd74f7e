// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <mpi.h>
#include <petscksp.h>

#include <asyncfem/petscBackend/solverSettings.hpp>
#include <string>

#include "detail/petscHandle.hpp"

namespace asyncfem::detail {

/// The options database the solvers of one simulation read: `options` (the settings'
/// own), then every global option (command line, PetscRuntime's string) on top, so the
/// command line has the last word and one simulation's options do not leak into the next.
OptionsHandle makeSolverOptions(const std::string& options);

/// What one solve did: converged or not (PETSc's reason in words), and the iterations.
struct SolveOutcome {
  bool converged = true;
  int iterations = 0;
  std::string reason;
};

/// One linear solver of the distributed systems: a KSP and its PC, typed by
/// settings.kind, with settings' tolerances, then the options database (with the given
/// prefix) on top (KSPSetFromOptions). CG measures the unpreconditioned residual unless
/// the options choose a norm; iterative solves start from the solution vector passed in.
class LinearSolver {
 public:
  /// options: the database from makeSolverOptions (it must outlive the solver); prefix:
  /// the options prefix ("mass_") or empty; fixedOperator: an SPD matrix the solver keeps
  /// for its whole life (given before the options are applied), or nullptr to give one
  /// later with setOperator().
  LinearSolver(MPI_Comm comm, PetscOptions options, const PetscSolverSettings& settings, const std::string& prefix,
               Mat fixedOperator);

  /// Solves with matrix from now on (its preconditioner or factor is rebuilt on the next solve).
  void setOperator(Mat matrix);
  /// Solves with matrix, preconditioned by one built from preconditioning (both SPD).
  void setOperators(Mat matrix, Mat preconditioning);
  /// Builds the preconditioner or factor of the current operator now (KSPSetUp) instead of
  /// at the next solve.
  void setUp();
  /// Solves A x = b; x holds the initial guess of iterative solvers on entry.
  SolveOutcome solve(Vec b, Vec x);
  /// x = M^{-1} b, one application of the preconditioner of the current operator.
  void applyPreconditioner(Vec b, Vec x);
  /// The KSP and PC types PETSc resolved after the options database.
  std::string kspType() const;
  std::string pcType() const;

 private:
  KspHandle ksp_;
};

}  // namespace asyncfem::detail
