// SPDX-License-Identifier: BSD-3-Clause
#include "detail/freeSystem.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/contactBlock.hpp>
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
  freeToFull_ = free;
  extractor_ = SubmatrixExtractor(fullStiffness_, free, free);
  Eigen::SparseMatrix<double> fullMass = embedInPattern(system.mass, fullStiffness_, "mass matrix");
  mass = extractor_.extract(fullMass);
  stiffness = extractor_.extract(fullStiffness_);
  systemMatrix = stiffness;
}

void checkNewtonDiverged(const std::string& integratorName, double relativeResidual, int iterations,
                         const Eigen::VectorXd& residual, const FreeDofs& dofs, double time) {
  if (!(relativeResidual > 1.0)) return;  // converged, or still closer than the linearized step
  Eigen::Index largest = 0;
  if (residual.allFinite()) residual.cwiseAbs().maxCoeff(&largest);
  NumericalErrorLocation location;
  location.time = time;
  location.dof = dofs.freeToFull()[static_cast<std::size_t>(largest)];
  location.vertex = location.dof / 3;
  throw NumericalError(integratorName + ": Newton's iteration diverged in the step to time " + std::to_string(time) +
                           ": after " + std::to_string(iterations) + " iterations its residual is " +
                           std::to_string(relativeResidual) + " times the step's initial one, largest at DOF " +
                           std::to_string(location.dof) + " (vertex " + std::to_string(location.vertex) +
                           "); the state was left at the start of the step; enable lineSearch or reduce the step",
                       location);
}

namespace {

/// A force model's forces must be finite: a NaN would spread through the solve to every
/// DOF, and the integrator's own check could then only name the first of them.
void checkForcesFinite(const Eigen::VectorXd& forces, double stepTime) {
  for (Eigen::Index i = 0; i < forces.size(); ++i) {
    if (std::isfinite(forces[i])) continue;
    NumericalErrorLocation location;
    location.time = stepTime;
    location.dof = static_cast<int>(i);
    location.vertex = location.dof / 3;
    const std::string when = std::isfinite(stepTime) ? " in the step to time " + std::to_string(stepTime) : "";
    throw NumericalError("the force model returned a non-finite internal force (" + std::to_string(forces[i]) + ")" +
                             when + " at DOF " + std::to_string(location.dof) + " (vertex " +
                             std::to_string(location.vertex) + ", coordinate " + "xyz"[location.dof % 3] +
                             "); the state was left at the start of the step",
                         location);
  }
}

}  // namespace

void FreeSystem::evaluateForcesAndTangent(const DynamicSystem& system, const Eigen::VectorXd& displacement,
                                          Eigen::SparseMatrix<double>& into, IntegratorStats& stats) {
  {
    TimeInto timer(stats.forceSeconds);
    system.forceModel->forcesAndTangent(displacement, fullForces_, fullStiffness_);
    checkForcesFinite(fullForces_, stepTime);
  }
  TimeInto timer(stats.assemblySeconds);
  if (into.nonZeros() != stiffness.nonZeros()) into = stiffness;
  extractor_.update(fullStiffness_, into);
}

void FreeSystem::evaluateForces(const DynamicSystem& system, const Eigen::VectorXd& displacement,
                                IntegratorStats& stats) {
  TimeInto timer(stats.forceSeconds);
  system.forceModel->internalForces(displacement, fullForces_);
  checkForcesFinite(fullForces_, stepTime);
}

void FreeSystem::assemble(const std::vector<double>& coefficients,
                          const std::vector<const Eigen::SparseMatrix<double>*>& matrices, IntegratorStats& stats) {
  TimeInto timer(stats.assemblySeconds);
  combine(coefficients, matrices, systemMatrix);
}

void FreeSystem::addVertexBlocks(const FreeDofs& dofs, const VertexJacobian& jacobian, double stiffnessWeight,
                                 double dampingWeight, IntegratorStats& stats) {
  if (!jacobian.couplings.empty()) {
    // No room for the couplings' off-diagonal blocks in the pattern: their bounds instead.
    addVertexBlocks(dofs, boundCouplings(jacobian), stiffnessWeight, dampingWeight, stats);
    return;
  }
  TimeInto timer(stats.assemblySeconds);
  const std::vector<int>& fullToFree = dofs.fullToFree();
  const int* outer = systemMatrix.outerIndexPtr();
  const int* inner = systemMatrix.innerIndexPtr();
  double* values = systemMatrix.valuePtr();
  for (std::size_t k = 0; k < jacobian.vertices.size(); ++k) {
    const Eigen::Matrix3d block = contactStepBlock(dofs, jacobian, k, stiffnessWeight, dampingWeight);
    const int vertex = jacobian.vertices[k];
    for (int c = 0; c < 3; ++c) {
      const int column = fullToFree[static_cast<std::size_t>((3 * vertex) + c)];
      if (column < 0) continue;
      for (int r = 0; r < 3; ++r) {
        const int row = fullToFree[static_cast<std::size_t>((3 * vertex) + r)];
        if (row < 0) continue;
        const int* begin = inner + outer[column];
        const int* end = inner + outer[column + 1];
        const int* slot = std::lower_bound(begin, end, row);
        if (slot == end || *slot != row) {
          throw Error("vertex " + std::to_string(vertex) + "'s own 3 x 3 block is not in the system matrix's pattern");
        }
        values[slot - inner] += block(r, c);
      }
    }
  }
}

void FreeSystem::rethrowWithMeshDof(const NumericalError& error) const {
  const int column = error.location().dof;
  if (column < 0 || column >= static_cast<int>(freeToFull_.size())) throw error;
  NumericalErrorLocation location = error.location();
  location.dof = freeToFull_[static_cast<std::size_t>(column)];
  location.vertex = location.dof / 3;
  throw NumericalError(std::string(error.what()) + ", which is DOF " + std::to_string(location.dof) + " (vertex " +
                           std::to_string(location.vertex) + ", coordinate " + "xyz"[location.dof % 3] +
                           ") of the mesh",
                       location);
}

void FreeSystem::factorize(IntegratorStats& stats) {
  TimeInto timer(stats.factorizationSeconds);
  if (!analyzed_) {
    solver_->analyzePattern(systemMatrix);
    analyzed_ = true;
  }
  try {
    solver_->factorize(systemMatrix);
  } catch (const NumericalError& error) {
    rethrowWithMeshDof(error);
  }
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

void FreeSystem::solve(const Eigen::MatrixXd& rhs, Eigen::MatrixXd& x, IntegratorStats& stats) {
  TimeInto timer(stats.solveSeconds);
  solver_->solve(rhs, x);
  stats.solvedRightHandSides += rhs.cols();
  stats.solveFlops += static_cast<double>(rhs.cols()) * solver_->stats().solveFlopsPerRhs;
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
