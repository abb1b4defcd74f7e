// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <limits>
#include <memory>
#include <string>
#include <vector>

// Internals shared by the single-rate integrators: the free-DOF matrices, their
// factorization with timing and counters, the mass solve and the state checks.
namespace asyncfem::detail {

/// The values of matrix re-expressed in the sparsity pattern of pattern (zeros where
/// matrix has no entry). Throws asyncfem::ValidationError naming the entry if matrix has
/// a non-zero value outside pattern. what names matrix in that message.
Eigen::SparseMatrix<double> embedInPattern(const Eigen::SparseMatrix<double>& matrix,
                                           const Eigen::SparseMatrix<double>& pattern, const std::string& what);

/// True when every stored off-diagonal value of matrix is zero.
bool isDiagonal(const Eigen::SparseMatrix<double>& matrix);

/// free = the free entries of full (resized), without allocating when sizes already match.
void restrictTo(const FreeDofs& dofs, const Eigen::VectorXd& full, Eigen::VectorXd& free);
/// full = free scattered to the full numbering, fixed entries exactly zero.
void expandTo(const FreeDofs& dofs, const Eigen::VectorXd& free, Eigen::VectorXd& full);

/// Adds the wall time of its lifetime to a stats field (one of IntegratorStats' seconds).
class TimeInto {
 public:
  explicit TimeInto(double& seconds) : seconds_(seconds) { watch_.start(); }
  ~TimeInto() { seconds_ += watch_.stop(); }
  TimeInto(const TimeInto&) = delete;
  TimeInto& operator=(const TimeInto&) = delete;

 private:
  double& seconds_;
  Stopwatch watch_;
};

/// Free-DOF matrices of a DynamicSystem and one factorization of a linear combination of
/// them. Every free matrix shares the pattern of the force model's stiffness restricted
/// to the free DOFs, so combinations are value-wise sums (combine()).
class FreeSystem {
 public:
  FreeSystem(const DynamicSystem& system, SolverKind solverKind);

  /// Evaluates f_int(u) and K(u) (u full) with the force model, then copies the free
  /// values of K into `into` (a free matrix from this object). Adds to stats.
  void evaluateForcesAndTangent(const DynamicSystem& system, const Eigen::VectorXd& displacement,
                                Eigen::SparseMatrix<double>& into, IntegratorStats& stats);
  /// f_int(u) only (full), into fullForces().
  void evaluateForces(const DynamicSystem& system, const Eigen::VectorXd& displacement, IntegratorStats& stats);

  /// systemMatrix = sum_i coefficients[i] * matrices[i] (free matrices of this object).
  void assemble(const std::vector<double>& coefficients,
                const std::vector<const Eigen::SparseMatrix<double>*>& matrices, IntegratorStats& stats);
  /// systemMatrix += every contactStepBlock of jacobian on its vertex's free DOFs (the
  /// symmetric positive semi-definite part, so that the matrix stays one for Cholesky). The blocks lie in the pattern
  /// (a vertex's own block is in K's). Couplings go in as their per-vertex bounds
  /// (boundCouplings): the pattern has no room for their off-diagonal blocks.
  void addVertexBlocks(const FreeDofs& dofs, const VertexJacobian& jacobian, double stiffnessWeight,
                       double dampingWeight, IntegratorStats& stats);
  /// Numeric factorization of systemMatrix (symbolic analysis the first time only). A
  /// solver's NumericalError that names a column (location().dof) is thrown again with
  /// the mesh DOF and vertex that column stands for.
  void factorize(IntegratorStats& stats);
  /// Throws error again, with the mesh DOF and vertex of the free column it names
  /// (location().dof) added to its message and location; as is when it names none.
  [[noreturn]] void rethrowWithMeshDof(const NumericalError& error) const;
  /// x = systemMatrix^{-1} rhs with the last factorization.
  void solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x, IntegratorStats& stats);
  /// X = systemMatrix^{-1} B (several right-hand sides) with the last factorization.
  void solve(const Eigen::MatrixXd& rhs, Eigen::MatrixXd& x, IntegratorStats& stats);

  const Eigen::VectorXd& fullForces() const { return fullForces_; }
  SparseSolver& solver() { return *solver_; }
  const SparseSolver& solver() const { return *solver_; }

  Eigen::SparseMatrix<double> mass;              ///< M on the free DOFs
  Eigen::SparseMatrix<double> stiffness;         ///< K on the free DOFs (constant, or tangent at step start)
  Eigen::SparseMatrix<double> iterateStiffness;  ///< K at a Newton iterate (free)
  Eigen::SparseMatrix<double> systemMatrix;      ///< the combination last assembled
  /// The end time of the step being computed, for messages (NaN: not in a step). The
  /// evaluate functions throw NumericalError naming it and the DOF when the force model
  /// returns a non-finite force.
  double stepTime = std::numeric_limits<double>::quiet_NaN();

 private:
  SubmatrixExtractor extractor_;
  Eigen::SparseMatrix<double> fullStiffness_;
  Eigen::VectorXd fullForces_;
  std::unique_ptr<SparseSolver> solver_;
  bool analyzed_ = false;
  Eigen::MatrixXd solution_;
  std::vector<int> freeToFull_;  ///< free index -> mesh DOF
};

/// Throws NumericalError when a Newton iteration that stopped unconverged (after its
/// iterations) diverged: its residual grew beyond the step's initial one
/// (relativeResidual > 1). Names the integrator, the step's end time, the iterations and
/// the vertex with the largest residual (residual on the free DOFs of dofs).
void checkNewtonDiverged(const std::string& integratorName, double relativeResidual, int iterations,
                         const Eigen::VectorXd& residual, const FreeDofs& dofs, double time);

/// Solves M x = b on the free DOFs: a division for a diagonal (lumped) M, otherwise a
/// sparse Cholesky factored once.
class FreeMassSolver {
 public:
  FreeMassSolver() = default;
  /// Factors (or inverts the diagonal of) the free mass matrix; adds to stats.
  void setup(const Eigen::SparseMatrix<double>& freeMass, SolverKind kind, IntegratorStats& stats);
  bool diagonal() const { return diagonal_; }
  void solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x, IntegratorStats& stats);

 private:
  bool diagonal_ = false;
  Eigen::VectorXd inverseDiagonal_;
  std::unique_ptr<SparseSolver> solver_;
  Eigen::MatrixXd solution_;
};

}  // namespace asyncfem::detail
