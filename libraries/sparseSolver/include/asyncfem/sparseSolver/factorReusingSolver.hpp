// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <memory>

namespace asyncfem {

namespace detail {
class SinglePrecisionFactor;
}

/// When FactorReusingSolver refactors and how accurately it solves.
struct FactorReuseOptions {
  /// PCG stops once |b - A x|_2 <= relativeTolerance |b|_2.
  double relativeTolerance = 1e-8;
  /// A solve that has not converged after this many PCG iterations is abandoned: the
  /// current matrix is factored and the system solved with the new factor (exactly).
  int maxIterations = 25;
  /// After a converged solve that took more than this many iterations, the next
  /// setMatrix() refactors.
  int refactorAfterIterations = 20;
  /// ... and also when the count exceeds growthFactor times the count of the first solve
  /// with the current factor's stale values, at least 2 iterations (<= 0: off).
  double growthFactor = 0.0;
  /// ... and also when refactoring pays (amortisation): with the cost of a factorization
  /// counted as this many PCG iterations, the next setMatrix() refactors once the last
  /// solve's iterations exceed the average cost per solve since the last factorization
  /// (factorization and its exact solve included), the point where a longer cycle only
  /// raises the average. <= 0 (default): estimated from the direct solver's own counts as
  /// max(30, factorFlops / (6 solveFlopsPerRhs)) with the single-precision preconditioner
  /// below (20 instead of 30 with the double factor): about 30 iterations while the
  /// factorization's rate still grows with its supernodes, then 6 as the speed of a
  /// saturated supernodal factorization over the memory-bound substitutions (measured on
  /// CHOLMOD, docs/benchmarks.md "The kept factor in single precision"). Deterministic:
  /// iteration counts and flop counts only, never wall time.
  double factorCostInIterations = 0.0;
  /// Turns the amortisation rule off (only the two thresholds above apply).
  bool amortize = true;
  /// PCG preconditions with a single-precision copy of the kept factor when the direct
  /// solver is supernodal (CHOLMOD): each iteration then reads half the bytes, while the
  /// iteration still converges to relativeTolerance in double precision (the rounding
  /// only enters the preconditioner, as about 6e-8 of its output). The exact solve right
  /// after a factorization keeps the double factor. After each factorization the copy is
  /// checked against the double factor on a fixed vector and dropped (the double factor
  /// preconditions) when they differ by more than 1e-2 relatively (entries beyond
  /// float's range, or conditioning that amplifies the rounding). false: the double
  /// factor throughout.
  bool singlePrecisionPreconditioner = true;
};

/// Counters of a FactorReusingSolver since construction (or resetStats()).
struct FactorReuseStats {
  long long solves = 0;
  long long exactSolves = 0;                   ///< solves with a factor of the current values (no iteration)
  long long pcgIterations = 0;                 ///< sum over the PCG solves (one product with A each)
  long long refactorizations = 0;              ///< numeric factorizations, the first one included
  long long abandonedSolves = 0;               ///< PCG runs that hit maxIterations (then solved exactly)
  int lastIterations = 0;                      ///< PCG iterations of the last solve (0: exact)
  double factorCostInIterations = 0.0;         ///< the cost model in use (see FactorReuseOptions)
  double lastRelativeResidual = 0.0;           ///< |b - A x| / |b| of the last PCG solve (0 when exact)
  bool singlePrecisionPreconditioner = false;  ///< whether PCG runs on the single-precision copy (of the last factor)
};

/// What a FactorReusingSolver's refactorization rule carries from one solve to the next,
/// besides the kept factor itself: with the matrix that factor was computed from, enough
/// for another solver to continue exactly as this one would (checkpoints; ruleState(),
/// restoreRuleState()).
struct FactorReuseRuleState {
  bool hasFactor = false;        ///< a factor is kept (false before the first factorization)
  bool refactorPending = true;   ///< the next setMatrix() factors its matrix (the kept factor is not needed)
  int firstStaleIterations = 0;  ///< PCG iterations of the first solve with the kept factor (0: none yet)
  double cycleCost = 0.0;        ///< the factorization and the PCG iterations since it, in PCG iterations
  long long cycleSolves = 0;     ///< solves since the last factorization
};

/// Solves a sequence of systems A_k x = b_k whose matrices (one sparsity pattern, SPD,
/// e.g. the backward Euler matrices M + h D + h^2 K(u_k) of a corotational model) change
/// slowly: the last numeric factorization of some earlier A_j is kept as the
/// preconditioner P = A_j^{-1} of a conjugate-gradient solve with A_k, until the
/// iteration count says that A_k has moved too far (FactorReuseOptions), when A_k is
/// factored again. A solve right after a factorization is one back-substitution.
///
/// Each PCG iteration costs one sparse product with A and one back-substitution with
/// the kept factor, against one numeric factorization (typically 10-20 back-substitutions
/// on 3D meshes) for the exact path, so a step costs a few back-substitutions while the
/// factor stays a good preconditioner. The solution meets the relative residual
/// tolerance; it is not the exact solve's to rounding (the difference is at most
/// cond(A) times the tolerance, relatively). Deterministic: the same sequence of inputs
/// gives the same results.
class FactorReusingSolver {
 public:
  /// direct: the factorization used (cholmod for SPD matrices). Throws asyncfem::Error on
  /// options out of range (tolerance not in [0, 1), maxIterations < 1).
  explicit FactorReusingSolver(SolverKind direct = SolverKind::cholmod, const FactorReuseOptions& options = {});
  ~FactorReusingSolver();
  FactorReusingSolver(const FactorReusingSolver&) = delete;
  FactorReusingSolver& operator=(const FactorReusingSolver&) = delete;

  /// The matrix of the following solves (square, compressed; must stay alive and
  /// unchanged until then). Analyses its pattern the first time or when it changes, and
  /// factors it when there is no factor yet or the policy asked for a refactorization.
  void setMatrix(const Eigen::SparseMatrix<double>& matrix);
  /// x = A^{-1} b to the relative tolerance (exactly when the factor is A's own). Throws
  /// asyncfem::Error before setMatrix() or on a size mismatch; NumericalError when the
  /// factorization fails (A not positive definite for Cholesky).
  void solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution);
  /// Same, with PCG starting from initialGuess (e.g. the previous step's solution, when
  /// consecutive systems have similar solutions) when its residual is below |b|;
  /// otherwise from 0. initialGuess may alias solution.
  void solve(const Eigen::VectorXd& rhs, const Eigen::VectorXd& initialGuess, Eigen::VectorXd& solution);
  /// Makes the next setMatrix() factor its matrix.
  void requestRefactorization() { refactorPending_ = true; }
  /// The rule's state between solves (call it between a solve and the next setMatrix()).
  FactorReuseRuleState ruleState() const;
  /// Continues as the solver that `state` was taken from: when that solver kept a factor
  /// it still meant to use (hasFactor and not refactorPending), factors keptMatrix, the
  /// matrix of that factor rebuilt bit for bit by the caller (it must stay alive until the
  /// next setMatrix(), like setMatrix()'s argument; counted in stats().refactorizations),
  /// then takes the rule's counters. The following setMatrix() and solve() calls then give
  /// that solver's results bit for bit (same direct solver, threads and options). Throws
  /// asyncfem::Error when keptMatrix is needed and null, or the counters are out of range;
  /// NumericalError when the factorization fails.
  void restoreRuleState(const FactorReuseRuleState& state, const Eigen::SparseMatrix<double>* keptMatrix);

  const FactorReuseOptions& options() const { return options_; }
  const FactorReuseStats& stats() const { return stats_; }
  /// The direct solver's own counters (factor non-zeros, flops, times).
  const SolverStats& directStats() const { return direct_->stats(); }
  void resetStats() { stats_ = FactorReuseStats{}; }

 private:
  void refactor();
  /// Analyses matrix's pattern unless the last analysis was of one with its size and entry count.
  void analyseIfNeeded(const Eigen::SparseMatrix<double>& matrix);
  void applyPreconditioner(const Eigen::VectorXd& rhs, Eigen::VectorXd& out);
  void solveExactly(const Eigen::VectorXd& rhs, Eigen::VectorXd& out);
  void copySinglePrecisionFactor();

  FactorReuseOptions options_;
  FactorReuseStats stats_;
  std::unique_ptr<SparseSolver> direct_;
  std::unique_ptr<detail::SinglePrecisionFactor> singlePrecision_;  // null: precondition in double
  const Eigen::SparseMatrix<double>* matrix_ = nullptr;
  bool analysed_ = false;
  bool factorIsCurrent_ = false;  // the factor is that of matrix_'s current values
  bool refactorPending_ = true;
  bool hasFactor_ = false;        // a numeric factorization was made
  int firstStaleIterations_ = 0;  // iterations of the first PCG solve with this factor
  double cycleCost_ = 0.0;        // factorization + iterations since it, in PCG iterations
  long long cycleSolves_ = 0;     // solves since the last factorization
  Eigen::MatrixXd preconditioned_;
  Eigen::VectorXd residual_, direction_, product_, z_, previousZ_;
};

}  // namespace asyncfem
