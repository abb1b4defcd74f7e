// SPDX-License-Identifier: BSD-3-Clause
#include "detail/freeSystem.hpp"

#include <asyncfem/core/error.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <cmath>
#include <string>

namespace asyncfem::detail {

Eigen::SparseMatrix<double> embedInPattern(const Eigen::SparseMatrix<double>& matrix,
                                           const Eigen::SparseMatrix<double>& pattern, const std::string& what) {
  if (matrix.rows() != pattern.rows() || matrix.cols() != pattern.cols()) {
    throw ValidationError(what + " is " + std::to_string(matrix.rows()) + " x " + std::to_string(matrix.cols()) +
                          ", expected " + std::to_string(pattern.rows()) + " x " + std::to_string(pattern.cols()));
  }
  Eigen::SparseMatrix<double> out = pattern;
  out.makeCompressed();
  std::fill(out.valuePtr(), out.valuePtr() + out.nonZeros(), 0.0);
  for (int col = 0; col < matrix.outerSize(); ++col) {
    // Both columns have sorted row indices: one merge pass per column.
    Eigen::SparseMatrix<double>::InnerIterator target(out, col);
    for (Eigen::SparseMatrix<double>::InnerIterator it(matrix, col); it; ++it) {
      while (target && target.row() < it.row()) ++target;
      if (target && target.row() == it.row()) {
        target.valueRef() += it.value();
      } else if (it.value() != 0.0) {
        throw ValidationError(what + " has a non-zero entry (" + std::to_string(it.row()) + ", " + std::to_string(col) +
                              ") outside the force model's stiffness pattern");
      }
    }
  }
  return out;
}

bool isDiagonal(const Eigen::SparseMatrix<double>& matrix) {
  for (int col = 0; col < matrix.outerSize(); ++col) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(matrix, col); it; ++it) {
      if (it.row() != col && it.value() != 0.0) return false;
    }
  }
  return true;
}

void restrictTo(const FreeDofs& dofs, const Eigen::VectorXd& full, Eigen::VectorXd& free) {
  const std::vector<int>& map = dofs.freeToFull();
  free.resize(static_cast<Eigen::Index>(map.size()));
  for (std::size_t i = 0; i < map.size(); ++i) free[static_cast<Eigen::Index>(i)] = full[map[i]];
}

void expandTo(const FreeDofs& dofs, const Eigen::VectorXd& free, Eigen::VectorXd& full) {
  const std::vector<int>& map = dofs.freeToFull();
  full.setZero(dofs.numDofs());
  for (std::size_t i = 0; i < map.size(); ++i) full[map[i]] = free[static_cast<Eigen::Index>(i)];
}

FreeSystem::FreeSystem(const DynamicSystem& system, SolverKind solverKind) : solver_(makeSparseSolver(solverKind)) {
  fullStiffness_ = system.forceModel->createStiffnessMatrix();
  fullStiffness_.makeCompressed();
  const std::vector<int>& free = system.freeDofs.freeToFull();
  extractor_ = SubmatrixExtractor(fullStiffness_, free, free);
  Eigen::SparseMatrix<double> fullMass = embedInPattern(system.mass, fullStiffness_, "mass matrix");
  mass = extractor_.extract(fullMass);
  stiffness = extractor_.extract(fullStiffness_);
  systemMatrix = stiffness;
}

void FreeSystem::evaluateForcesAndTangent(const DynamicSystem& system, const Eigen::VectorXd& displacement,
                                          Eigen::SparseMatrix<double>& into, IntegratorStats& stats) {
  {
    TimeInto timer(stats.forceSeconds);
    system.forceModel->forcesAndTangent(displacement, fullForces_, fullStiffness_);
  }
  TimeInto timer(stats.assemblySeconds);
  if (into.nonZeros() != stiffness.nonZeros()) into = stiffness;
  extractor_.update(fullStiffness_, into);
}

void FreeSystem::evaluateForces(const DynamicSystem& system, const Eigen::VectorXd& displacement,
                                IntegratorStats& stats) {
  TimeInto timer(stats.forceSeconds);
  system.forceModel->internalForces(displacement, fullForces_);
}

void FreeSystem::assemble(const std::vector<double>& coefficients,
                          const std::vector<const Eigen::SparseMatrix<double>*>& matrices, IntegratorStats& stats) {
  TimeInto timer(stats.assemblySeconds);
  combine(coefficients, matrices, systemMatrix);
}

void FreeSystem::factorize(IntegratorStats& stats) {
  TimeInto timer(stats.factorizationSeconds);
  if (!analyzed_) {
    solver_->analyzePattern(systemMatrix);
    analyzed_ = true;
  }
  solver_->factorize(systemMatrix);
  ++stats.factorizations;
  stats.factorFlops += solver_->stats().factorFlops;
}

void FreeSystem::solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x, IntegratorStats& stats) {
  TimeInto timer(stats.solveSeconds);
  solver_->solve(rhs, solution_);
  x = solution_.col(0);
  ++stats.solvedRightHandSides;
  stats.solveFlops += solver_->stats().solveFlopsPerRhs;
}

void FreeMassSolver::setup(const Eigen::SparseMatrix<double>& freeMass, SolverKind kind, IntegratorStats& stats) {
  TimeInto timer(stats.factorizationSeconds);
  diagonal_ = isDiagonal(freeMass);
  if (diagonal_) {
    inverseDiagonal_ = freeMass.diagonal();
    for (Eigen::Index i = 0; i < inverseDiagonal_.size(); ++i) {
      if (!(inverseDiagonal_[i] > 0.0)) {
        throw NumericalError("mass matrix has a non-positive diagonal entry " + std::to_string(inverseDiagonal_[i]) +
                             " at free DOF " + std::to_string(i));
      }
      inverseDiagonal_[i] = 1.0 / inverseDiagonal_[i];
    }
    solver_.reset();
    return;
  }
  solver_ = makeSparseSolver(kind);
  solver_->compute(freeMass);
  ++stats.factorizations;
  stats.factorFlops += solver_->stats().factorFlops;
}

void FreeMassSolver::solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x, IntegratorStats& stats) {
  TimeInto timer(stats.solveSeconds);
  if (diagonal_) {
    x = rhs.cwiseProduct(inverseDiagonal_);
    return;
  }
  solver_->solve(rhs, solution_);
  x = solution_.col(0);
  ++stats.solvedRightHandSides;
  stats.solveFlops += solver_->stats().solveFlopsPerRhs;
}

}  // namespace asyncfem::detail
