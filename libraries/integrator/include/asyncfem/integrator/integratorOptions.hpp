// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/sparseSolver/sparseSolver.hpp>

namespace asyncfem {

/// Settings shared by the single-rate integrators; each integrator reads the fields that
/// concern it and ignores the others.
struct IntegratorOptions {
  /// Factorization used for the implicit system matrices and for a consistent mass
  /// matrix (explicit methods). The matrices are SPD once fixed DOFs are removed.
  SolverKind solver = SolverKind::cholmod;

  /// Implicit methods, nonlinear force models only: iterations per step. 1 is the
  /// linearized step (tangent at the start of the step, as Vega FEM does); more
  /// iterations run Newton on the nonlinear step equations until the residual norm falls
  /// below tolerance times the norm of the linearized right-hand side. Linear force
  /// models solve the step equations exactly with one iteration and ignore this.
  int maxIterations = 1;
  /// Relative Newton tolerance (see maxIterations).
  double tolerance = 1e-8;
  /// Backward Euler with implicit contact (DynamicSystem::externalForceJacobian): Newton
  /// iterations allowed for a step whose prediction or end state has vertices in contact,
  /// with the contact force and its derivatives at each iterate, until the residual meets
  /// tolerance (linear force models too). The larger of this and maxIterations applies.
  int contactIterations = 10;
  /// Backward Euler, linear models with implicit contact: solve a step with contact by a
  /// low-rank (Woodbury) update of the kept contact-free factor where its flops are below a
  /// factorization's; false: always the contact step's own matrix (factored, or kept-factor
  /// PCG under reuseFactor).
  bool contactLowRank = true;
  /// Backward Euler with maxIterations > 1: backtrack every Newton update (the
  /// linearized first one included) until the incremental potential decreases, so that a
  /// large step cannot diverge (see BackwardEuler). No effect with maxIterations = 1,
  /// which keeps the linearized step exactly.
  bool lineSearch = true;
  /// Backward Euler Newton iterations: evaluate the Rayleigh term beta K at every iterate,
  /// D = alpha M + beta K(u_{k+1}^(i)), as Vega FEM does. Off (the default): D keeps
  /// K(u_k) of the step start, so the step equations are the gradient of a potential.
  bool rayleighStiffnessAtIterate = false;

  /// Backward Euler, nonlinear force models (the default): instead of refactoring the
  /// system matrix at every step, keep the last numeric factor as the preconditioner of a
  /// PCG solve to pcgTolerance (relative residual) and refactor when PCG needs more than
  /// pcgRefactorIterations iterations or refactoring pays (FactorReusingSolver); the kept
  /// factor lives across frames, and its state is in checkpoints
  /// (BackwardEuler::internalState()), so that a run resumed from a checkpoint continues
  /// bit for bit. Trajectories stay within 1e-8 of the exact path's
  /// relative to the largest displacement (test DefaultSolvePath.*, docs/benchmarks.md,
  /// "The default linear-solve path"). false: the exact path, one factorization and
  /// back-substitution per linear solve (Vega FEM's trajectory to rounding).
  bool reuseFactor = true;
  /// Relative residual tolerance of those PCG solves (reuseFactor only), in (0, 1). 1e-10
  /// keeps trajectories within 1e-8 of exact solves on strongly nonlinear motion, where
  /// 1e-8 did not (1.8e-8 on NonlinearAsync's bent corotational bar).
  double pcgTolerance = 1e-10;
  /// Iterations of a PCG solve above which the next step refactors (reuseFactor only).
  int pcgRefactorIterations = 8;
  /// The price of one numeric factorization in PCG iterations, for the rule that
  /// refactors once that pays (reuseFactor only; FactorReuseOptions::factorCostInIterations).
  /// <= 0 (the default): estimated from the factorization's own flop counts.
  double pcgFactorCost = 0.0;
  /// Precondition PCG with a single-precision copy of the kept factor (CHOLMOD only;
  /// FactorReuseOptions::singlePrecisionPreconditioner). false: the double factor.
  bool pcgSinglePrecision = true;

  /// Explicit methods: an upper bound of the highest angular frequency omega_max
  /// (rad / time unit) of the free system, e.g. from estimateMaxFrequency(mesh, massType).
  /// <= 0: the integrator estimates it from the matrices (see stableTimestep.hpp).
  double maxFrequency = 0.0;
  /// Explicit methods: run even when the timestep exceeds the stable estimate.
  bool force = false;
};

}  // namespace asyncfem
