// SPDX-License-Identifier: BSD-3-Clause
// The single-rate system A = M + hL D + hL^2 K on every free DOF, factored once and
// shared by every partition: a preconditioner for H^{LL*} that needs no set-up per
// partition (docs/asynchronous-integrator.md, "Quick set-up"). Private to the library.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <memory>
#include <vector>

namespace asyncfem::detail {

class WholeSystemFactor {
 public:
  using SparseMatrix = Eigen::SparseMatrix<double>;

  /// Factors A = (1 + hL alpha) M + (hL beta + hL^2) K on the free DOFs (global ids,
  /// ascending), K the tangent given. Symbolic analysis the first time only.
  void factor(const SparseMatrix& mass, const SparseMatrix& stiffness, const std::vector<int>& freeDofs,
              double largeStep, double alpha, double beta, IntegratorStats& stats);
  /// Whether a factor for this large step exists.
  bool factoredFor(double largeStep) const { return factored_ && largeStep_ == largeStep; }
  /// z = the L rows of A^{-1} [0; r]: the inverse of the Schur complement of A on L
  /// (Eq. Q1), r and z indexed like largeDofs (global ids, ascending).
  void solveOnLarge(const std::vector<int>& largeDofs, const Eigen::VectorXd& r, Eigen::VectorXd& z);
  /// Flops of the last numeric factorization and of one solve (what a factor of H^{LL*}
  /// and a solve with it cost, about).
  double factorFlops() const { return solver_ ? solver_->stats().factorFlops : 0.0; }
  double solveFlops() const { return solver_ ? solver_->stats().solveFlopsPerRhs : 0.0; }
  const SparseSolver* solver() const { return solver_.get(); }

 private:
  std::unique_ptr<SparseSolver> solver_;
  SubmatrixExtractor massCut_, stiffCut_;
  SparseMatrix mass_, stiffness_, system_;
  std::vector<int> freePosition_;  // global DOF -> position among the free DOFs (-1: fixed)
  bool cut_ = false, analyzed_ = false, factored_ = false;
  double largeStep_ = 0.0;
  Eigen::VectorXd rhs_;
  Eigen::MatrixXd solution_;
};

}  // namespace asyncfem::detail
