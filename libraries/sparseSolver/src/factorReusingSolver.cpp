// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/sparseSolver/factorReusingSolver.hpp>
#include <cmath>
#include <string>

namespace asyncfem {

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

FactorReusingSolver::~FactorReusingSolver() = default;

void FactorReusingSolver::setMatrix(const Eigen::SparseMatrix<double>& matrix) {
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
  if (refactorPending_) refactor();
}

void FactorReusingSolver::refactor() {
  direct_->factorize(*matrix_);
  ++stats_.refactorizations;
  factorIsCurrent_ = true;
  refactorPending_ = false;
  firstStaleIterations_ = 0;
  double factorCost = options_.factorCostInIterations;
  if (!(factorCost > 0.0)) {
    const SolverStats& direct = direct_->stats();
    factorCost = direct.solveFlopsPerRhs > 0.0 ? direct.factorFlops / (6.0 * direct.solveFlopsPerRhs) : 10.0;
  }
  stats_.factorCostInIterations = factorCost;
  // The factorization and the exact solve that follows it (one substitution).
  cycleCost_ = factorCost + 1.0;
  cycleSolves_ = 0;
}

void FactorReusingSolver::applyPreconditioner(const Eigen::VectorXd& rhs, Eigen::VectorXd& out) {
  direct_->solve(rhs, preconditioned_);
  out = preconditioned_.col(0);
}

void FactorReusingSolver::solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution) {
  solve(rhs, Eigen::VectorXd(), solution);
}

void FactorReusingSolver::solve(const Eigen::VectorXd& rhs, const Eigen::VectorXd& initialGuess,
                                Eigen::VectorXd& solution) {
  if (matrix_ == nullptr) throw Error("FactorReusingSolver::solve: called before setMatrix()");
  if (rhs.size() != matrix_->rows()) {
    throw Error("FactorReusingSolver::solve: right-hand side has " + std::to_string(rhs.size()) +
                " rows, the matrix has " + std::to_string(matrix_->rows()));
  }
  ++stats_.solves;
  if (factorIsCurrent_) {
    applyPreconditioner(rhs, solution);
    ++cycleSolves_;
    ++stats_.exactSolves;
    stats_.lastIterations = 0;
    stats_.lastRelativeResidual = 0.0;
    return;
  }
  // Preconditioned conjugate gradients (Saad, Iterative Methods, Alg. 9.1) from x = 0 or
  // from the initial guess.
  const Eigen::SparseMatrix<double>& a = *matrix_;
  const double rhsNorm = rhs.norm();
  if (rhsNorm == 0.0) {
    solution.setZero(rhs.size());
    stats_.lastIterations = 0;
    stats_.lastRelativeResidual = 0.0;
    return;
  }
  const double target = options_.relativeTolerance * rhsNorm;
  residual_ = rhs;
  bool fromGuess = false;
  if (initialGuess.size() == rhs.size()) {
    product_.noalias() = a * initialGuess;
    fromGuess = (rhs - product_).norm() < rhsNorm;
  }
  if (fromGuess) {
    if (&solution != &initialGuess) solution = initialGuess;
    residual_ -= product_;
  } else {
    solution.setZero(rhs.size());
  }
  applyPreconditioner(residual_, z_);
  direction_ = z_;
  double residualDotZ = residual_.dot(z_);
  int iterations = 0;
  double residualNorm = residual_.norm();
  while (residualNorm > target && iterations < options_.maxIterations) {
    product_.noalias() = a * direction_;
    const double curvature = direction_.dot(product_);
    if (!(curvature > 0.0) || !std::isfinite(curvature)) break;  // not SPD along p: solve exactly below
    const double step = residualDotZ / curvature;
    solution.noalias() += step * direction_;
    residual_.noalias() -= step * product_;
    ++iterations;
    residualNorm = residual_.norm();
    if (residualNorm <= target) break;
    applyPreconditioner(residual_, z_);
    const double nextDot = residual_.dot(z_);
    direction_ = z_ + (nextDot / residualDotZ) * direction_;
    residualDotZ = nextDot;
  }
  stats_.pcgIterations += iterations;
  stats_.lastIterations = iterations;
  if (!(residualNorm <= target)) {
    // The kept factor is no longer a useful preconditioner: factor A and solve exactly.
    ++stats_.abandonedSolves;
    refactor();
    applyPreconditioner(rhs, solution);
    ++cycleSolves_;
    stats_.lastRelativeResidual = 0.0;
    return;
  }
  stats_.lastRelativeResidual = residualNorm / rhsNorm;
  if (firstStaleIterations_ == 0) firstStaleIterations_ = iterations;
  const bool tooMany = iterations > options_.refactorAfterIterations;
  const bool grew = options_.growthFactor > 0.0 &&
                    static_cast<double>(iterations) >
                        std::max(2.0, options_.growthFactor * static_cast<double>(firstStaleIterations_));
  cycleCost_ += iterations;
  ++cycleSolves_;
  const bool pays =
      options_.amortize && static_cast<double>(iterations) > cycleCost_ / static_cast<double>(cycleSolves_);
  if (tooMany || grew || pays) refactorPending_ = true;
}

}  // namespace asyncfem
