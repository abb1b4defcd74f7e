// SPDX-License-Identifier: BSD-3-Clause
// The reference solve of one asynchronous large step: the whole block system of Eq. (A3),
// (sum_i m_i |S_i| + |L|) unknowns, assembled and factored by sparse LU. O(m) larger
// factors than the structured solve; kept to check it. Private to the library.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <memory>
#include <vector>

#include "detail/fastRegion.hpp"

namespace asyncfem::detail {

class NaiveSolver {
 public:
  NaiveSolver();
  /// Assembles the block lower-Hessenberg system from the regions' current blocks and
  /// largeSystem (Â^L) and factors it (symbolic analysis once per partition). Adds to stats.
  void factor(const std::vector<FastRegion>& regions, const Eigen::SparseMatrix<double>& largeSystem,
              const RegionPartition& partition, bool damped, IntegratorStats& stats);
  /// Solves with the right-hand sides b^S of every region (FastRegion::rhs) and b^L:
  /// every region's x gets its substeps X_1..X_m (substituted), largeSolution gets Y.
  void solve(std::vector<FastRegion>& regions, const Eigen::VectorXd& largeRhs, Eigen::VectorXd& largeSolution);
  /// One solve with a random right-hand side (for timing the solve floor).
  void solveRandom() { solver_->solve(Eigen::VectorXd::Random(system_.rows())); }
  /// Forgets the analysis (a new partition).
  void reset();
  const SparseSolver& solver() const { return *solver_; }
  Eigen::Index size() const { return system_.rows(); }

 private:
  Eigen::SparseMatrix<double> system_;
  std::unique_ptr<SparseSolver> solver_;
  bool analyzed_ = false;
  std::vector<int> offsets_;  // first row of region i's X_1; last entry = first row of Y
};

}  // namespace asyncfem::detail
