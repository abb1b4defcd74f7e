// SPDX-License-Identifier: BSD-3-Clause
// The whole single-rate system's factor as a partition-independent preconditioner.
#include "detail/wholeSystemFactor.hpp"

#include <asyncfem/integrator/stepFormula.hpp>

#include "detail/multirateSupport.hpp"
#include "detail/sparseBlocks.hpp"

namespace asyncfem::detail {

void WholeSystemFactor::factor(const SparseMatrix& mass, const SparseMatrix& stiffness,
                               const std::vector<int>& freeDofs, double largeStep, double alpha, double beta,
                               IntegratorStats& stats) {
  if (!cut_) {
    massCut_ = SubmatrixExtractor(mass, freeDofs, freeDofs);
    stiffCut_ = SubmatrixExtractor(stiffness, freeDofs, freeDofs);
    mass_ = massCut_.extract(mass);
    stiffness_ = stiffCut_.extract(stiffness);
    freePosition_.assign(static_cast<std::size_t>(mass.rows()), -1);
    for (std::size_t k = 0; k < freeDofs.size(); ++k) freePosition_[static_cast<std::size_t>(freeDofs[k])] = int(k);
    solver_ = makeSparseSolver(SolverKind::cholmod);
    cut_ = true;
  } else {
    stiffCut_.update(stiffness, stiffness_);
  }
  const stepFormula::MatrixWeights weights = stepFormula::backwardEuler::systemMatrix(largeStep, alpha, beta);
  combineInto(weights.mass, mass_, weights.stiffness, stiffness_, system_);
  factorizeCounted(*solver_, system_, analyzed_, stats);
  factored_ = true;
  largeStep_ = largeStep;
}

// With A = [A^SS A^SL; A^LS A^LL] (S: every DOF not in L), the L block of A^{-1} is the
// inverse of the Schur complement A^LL - A^LS (A^SS)^{-1} A^SL.
void WholeSystemFactor::solveOnLarge(const std::vector<int>& largeDofs, const Eigen::VectorXd& r, Eigen::VectorXd& z) {
  rhs_.setZero(system_.rows());
  for (std::size_t k = 0; k < largeDofs.size(); ++k)
    rhs_[freePosition_[static_cast<std::size_t>(largeDofs[k])]] = r[static_cast<Eigen::Index>(k)];
  solver_->solve(rhs_, solution_);
  z.resize(static_cast<Eigen::Index>(largeDofs.size()));
  for (std::size_t k = 0; k < largeDofs.size(); ++k)
    z[static_cast<Eigen::Index>(k)] = solution_(freePosition_[static_cast<std::size_t>(largeDofs[k])], 0);
}

}  // namespace asyncfem::detail
