// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/sparseSolver/factorReusingSolver.hpp>
#include <cmath>
#include <string>

#include "detail/singlePrecisionFactor.hpp"

namespace asyncfem {

namespace {

// Throws Error unless a matrix is set and rhs has its number of rows.
void checkSolveInput(const Eigen::SparseMatrix<double>* matrix, const Eigen::VectorXd& rhs) {
  if (matrix == nullptr) throw Error("FactorReusingSolver::solve: called before setMatrix()");
  if (rhs.size() != matrix->rows()) {
    throw Error("FactorReusingSolver::solve: right-hand side has " + std::to_string(rhs.size()) +
                " rows, the matrix has " + std::to_string(matrix->rows()));
  }
}

// Records a solve that took no PCG iteration (exact, or a zero right-hand side).
void recordNoIterations(FactorReuseStats& stats) {
  stats.lastIterations = 0;
  stats.lastRelativeResidual = 0.0;
}

// Start of the iteration: x = initialGuess when it has rhs's size and a smaller residual
// than x = 0 (then product = A x0), else x = 0; residual = rhs - A x.
void startFromGuessOrZero(const Eigen::SparseMatrix<double>& a, const Eigen::VectorXd& rhs, double rhsNorm,
                          const Eigen::VectorXd& initialGuess, Eigen::VectorXd& solution, Eigen::VectorXd& residual,
                          Eigen::VectorXd& product) {
  residual = rhs;
  bool fromGuess = false;
  if (initialGuess.size() == rhs.size()) {
    product.noalias() = a * initialGuess;
    fromGuess = (rhs - product).norm() < rhsNorm;
  }
  if (fromGuess) {
    if (&solution != &initialGuess) solution = initialGuess;
    residual -= product;
  } else {
    solution.setZero(rhs.size());
  }
}

// Preconditioned conjugate gradients (Saad, Iterative Methods, Alg. 9.1) from solution
// with its residual, until |residual| <= target, maxIterations, or a direction along
// which A is not positive. The direction update takes the Polak-Ribiere form
// beta = r_new . (z_new - z_old) / r_old . z_old (flexible CG, Notay 2000), equal to
// Alg. 9.1's in exact arithmetic with a symmetric preconditioner and robust when the
// preconditioner is applied in single precision. Returns the iterations; residualNorm is
// |residual| at the end. z, previousZ, direction and product are scratch.
template <class Preconditioner>
int preconditionedConjugateGradients(const Eigen::SparseMatrix<double>& a, double target, int maxIterations,
                                     const Preconditioner& precondition, Eigen::VectorXd& solution,
                                     Eigen::VectorXd& residual, Eigen::VectorXd& z, Eigen::VectorXd& previousZ,
                                     Eigen::VectorXd& direction, Eigen::VectorXd& product, double& residualNorm) {
  precondition(residual, z);
  direction = z;
  double residualDotZ = residual.dot(z);
  int iterations = 0;
  residualNorm = residual.norm();
  while (residualNorm > target && iterations < maxIterations) {
    product.noalias() = a * direction;
    const double curvature = direction.dot(product);
    if (!(curvature > 0.0) || !std::isfinite(curvature)) break;  // not SPD along p: solve exactly below
    const double step = residualDotZ / curvature;
    solution.noalias() += step * direction;
    residual.noalias() -= step * product;
    ++iterations;
    residualNorm = residual.norm();
    if (residualNorm <= target) break;
    previousZ.swap(z);
    precondition(residual, z);
    const double nextDot = residual.dot(z);
    const double beta = (nextDot - residual.dot(previousZ)) / residualDotZ;
    direction = z + beta * direction;
    residualDotZ = nextDot;
  }
  return iterations;
}

// The price of a numeric factorization in PCG iterations (FactorReuseOptions). Two regimes,
// measured with CHOLMOD on the 2-core machine of docs/benchmarks.md ("The kept factor in
// single precision"): while supernodes are small, the factorization's flop rate grows with
// its flops per factor entry q = factorFlops / solveFlopsPerRhs (4.3 GFLOP/s at q = 66, 14
// at q = 208) while the substitutions stay near 2 GFLOP/s, so the price hardly depends on
// the size there: 20-35 iterations on the bridge-sized mesh, 26-122 on box meshes up to
// 35k tets, the single-precision copy at the upper end (the floors below are the
// conservative side: amortisation is flat near its optimum). Once the dense kernels
// saturate, it costs q / 6 (measured 63 single, 47 double at 105k tets, where q / 6 = 64).
double estimatedFactorCost(const SolverStats& direct, bool singlePrecision) {
  const double floor = singlePrecision ? 30.0 : 20.0;
  if (!(direct.solveFlopsPerRhs > 0.0)) return floor;
  return std::max(floor, direct.factorFlops / (6.0 * direct.solveFlopsPerRhs));
}

// Whether the next setMatrix() should refactor after a converged PCG solve of iterations:
// too many iterations, growth against the first solve with this factor, or (amortize)
// more than the average cost per solve of the cycle so far.
bool refactorIsDue(const FactorReuseOptions& options, int iterations, int firstStaleIterations, double cycleCost,
                   long long cycleSolves) {
  const bool tooMany = iterations > options.refactorAfterIterations;
  const bool grew =
      options.growthFactor > 0.0 &&
      static_cast<double>(iterations) > std::max(2.0, options.growthFactor * static_cast<double>(firstStaleIterations));
  const bool pays = options.amortize && static_cast<double>(iterations) > cycleCost / static_cast<double>(cycleSolves);
  return tooMany || grew || pays;
}

}  // namespace

FactorReusingSolver::FactorReusingSolver(SolverKind direct, const FactorReuseOptions& options)
    : options_(options), direct_(makeSparseSolver(direct)) {
  if (!(options_.relativeTolerance >= 0.0 && options_.relativeTolerance < 1.0)) {
    throw Error("FactorReusingSolver: relativeTolerance must be in [0, 1) (got " +
                std::to_string(options_.relativeTolerance) + ")");
  }
  if (options_.maxIterations < 1) {
    throw Error("FactorReusingSolver: maxIterations must be >= 1 (got " + std::to_string(options_.maxIterations) + ")");
  }
}

FactorReusingSolver::~FactorReusingSolver() = default;  // where SinglePrecisionFactor is complete

void FactorReusingSolver::analyseIfNeeded(const Eigen::SparseMatrix<double>& matrix) {
  // A new size or entry count needs a new analysis; a pattern changed in place with the
  // same counts is caught by the direct solver's own check at the next factorization.
  const bool samePattern =
      analysed_ && matrix_ != nullptr && matrix.rows() == matrix_->rows() && matrix.nonZeros() == matrix_->nonZeros();
  matrix_ = &matrix;
  factorIsCurrent_ = false;
  if (!samePattern) {
    direct_->analyzePattern(matrix);
    analysed_ = true;
    refactorPending_ = true;
  }
}

void FactorReusingSolver::setMatrix(const Eigen::SparseMatrix<double>& matrix) {
  analyseIfNeeded(matrix);
  if (refactorPending_) refactor();
}

FactorReuseRuleState FactorReusingSolver::ruleState() const {
  FactorReuseRuleState state;
  state.hasFactor = hasFactor_;
  state.refactorPending = refactorPending_;
  state.firstStaleIterations = firstStaleIterations_;
  state.cycleCost = cycleCost_;
  state.cycleSolves = cycleSolves_;
  return state;
}

void FactorReusingSolver::restoreRuleState(const FactorReuseRuleState& state,
                                           const Eigen::SparseMatrix<double>* keptMatrix) {
  if (state.firstStaleIterations < 0 || state.cycleSolves < 0 || !(state.cycleCost >= 0.0) ||
      !std::isfinite(state.cycleCost)) {
    throw Error("FactorReusingSolver::restoreRuleState: counters out of range");
  }
  const bool needsFactor = state.hasFactor && !state.refactorPending;
  if (needsFactor) {
    if (keptMatrix == nullptr)
      throw Error("FactorReusingSolver::restoreRuleState: the kept factor's matrix is missing");
    analyseIfNeeded(*keptMatrix);
    refactor();
  }
  factorIsCurrent_ = false;
  refactorPending_ = !needsFactor;
  firstStaleIterations_ = state.firstStaleIterations;
  cycleCost_ = state.cycleCost;
  cycleSolves_ = state.cycleSolves;
}

void FactorReusingSolver::refactor() {
  direct_->factorize(*matrix_);
  ++stats_.refactorizations;
  hasFactor_ = true;
  copySinglePrecisionFactor();
  factorIsCurrent_ = true;
  refactorPending_ = false;
  firstStaleIterations_ = 0;
  double factorCost = options_.factorCostInIterations;
  if (!(factorCost > 0.0)) factorCost = estimatedFactorCost(direct_->stats(), singlePrecision_ != nullptr);
  stats_.factorCostInIterations = factorCost;
  // The factorization and the exact solve that follows it (one substitution).
  cycleCost_ = factorCost + 1.0;
  cycleSolves_ = 0;
}

void FactorReusingSolver::copySinglePrecisionFactor() {
  singlePrecision_.reset();
  const auto* source = dynamic_cast<const detail::SupernodalFactorSource*>(direct_.get());
  auto copy = std::make_unique<detail::SinglePrecisionFactor>();
  if (options_.singlePrecisionPreconditioner && source != nullptr && source->copyFactor(*copy) &&
      copy->agreesWith([this](const Eigen::VectorXd& rhs, Eigen::VectorXd& out) { solveExactly(rhs, out); })) {
    singlePrecision_ = std::move(copy);
  }
  stats_.singlePrecisionPreconditioner = singlePrecision_ != nullptr;
}

void FactorReusingSolver::applyPreconditioner(const Eigen::VectorXd& rhs, Eigen::VectorXd& out) {
  if (singlePrecision_) {
    singlePrecision_->solve(rhs, out);
  } else {
    solveExactly(rhs, out);
  }
}

void FactorReusingSolver::solveExactly(const Eigen::VectorXd& rhs, Eigen::VectorXd& out) {
  direct_->solve(rhs, preconditioned_);
  out = preconditioned_.col(0);
}

void FactorReusingSolver::solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution) {
  solve(rhs, Eigen::VectorXd(), solution);
}

void FactorReusingSolver::solve(const Eigen::VectorXd& rhs, const Eigen::VectorXd& initialGuess,
                                Eigen::VectorXd& solution) {
  checkSolveInput(matrix_, rhs);
  ++stats_.solves;
  if (factorIsCurrent_) {
    solveExactly(rhs, solution);
    ++cycleSolves_;
    ++stats_.exactSolves;
    recordNoIterations(stats_);
    return;
  }
  const double rhsNorm = rhs.norm();
  if (rhsNorm == 0.0) {
    solution.setZero(rhs.size());
    recordNoIterations(stats_);
    return;
  }
  const double target = options_.relativeTolerance * rhsNorm;
  startFromGuessOrZero(*matrix_, rhs, rhsNorm, initialGuess, solution, residual_, product_);
  const auto precondition = [this](const Eigen::VectorXd& in, Eigen::VectorXd& out) { applyPreconditioner(in, out); };
  double residualNorm = 0.0;
  const int iterations =
      preconditionedConjugateGradients(*matrix_, target, options_.maxIterations, precondition, solution, residual_, z_,
                                       previousZ_, direction_, product_, residualNorm);
  stats_.pcgIterations += iterations;
  stats_.lastIterations = iterations;
  if (!(residualNorm <= target)) {
    // The kept factor is no longer a useful preconditioner: factor A and solve exactly.
    ++stats_.abandonedSolves;
    refactor();
    solveExactly(rhs, solution);
    ++cycleSolves_;
    stats_.lastRelativeResidual = 0.0;
    return;
  }
  stats_.lastRelativeResidual = residualNorm / rhsNorm;
  if (firstStaleIterations_ == 0) firstStaleIterations_ = iterations;
  cycleCost_ += iterations;
  ++cycleSolves_;
  if (refactorIsDue(options_, iterations, firstStaleIterations_, cycleCost_, cycleSolves_)) refactorPending_ = true;
}

}  // namespace asyncfem
