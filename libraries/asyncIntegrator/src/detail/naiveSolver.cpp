// SPDX-License-Identifier: BSD-3-Clause
#include "detail/naiveSolver.hpp"

#include <asyncfem/core/stopwatch.hpp>

#include "detail/multirateSupport.hpp"
#include "detail/sparseBlocks.hpp"

namespace asyncfem::detail {

NaiveSolver::NaiveSolver() : solver_(makeSparseSolver(SolverKind::umfpack)) {}

void NaiveSolver::reset() {
  solver_ = makeSparseSolver(SolverKind::umfpack);
  analyzed_ = false;
}

namespace {

/// Region i's rows r = 1..m of Eq. (A3): A^S on the diagonal, M^{SS} - ... below it, B_r
/// at the interface columns of Y; and its E_j on L's interface rows.
void appendRegion(const FastRegion& rb, int offset, int largeOffset, const std::vector<int>& ifacePos, bool damped,
                  std::vector<Eigen::Triplet<double>>& triplets) {
  const int m = rb.ratio;
  const int s = static_cast<int>(rb.Mss.rows());
  const SparseMatrix C = rb.G - rb.Mss;
  const CouplingCoefficients& k = rb.coupling;
  for (int r = 1; r <= m; ++r) {
    const int row = offset + (r - 1) * s;
    appendTriplets(rb.systemMatrix, 1.0, row, row, triplets);
    if (r >= 2) appendTriplets(C, 1.0, row, row - s, triplets);
    for (int j = 1; j <= r - 2; ++j) appendTriplets(rb.G, 1.0, row, offset + (j - 1) * s, triplets);
    // B_r (Eq. A5 or A9), columns at the interface.
    SparseMatrix B = k.bM[r - 1] * rb.Msi + k.bK[r - 1] * rb.Ksi;
    if (damped) B += k.bD[r - 1] * rb.Dsi;
    appendTriplets(B, 1.0, row, largeOffset, triplets, nullptr, &ifacePos);
  }
  // Last row: E_j on X_j (Eq. A6 or A10), rows at the interface of L.
  for (int j = 1; j <= m; ++j) {
    SparseMatrix E = k.eM[j - 1] * rb.Mis + k.eK[j - 1] * rb.Kis;
    if (damped) E += k.eD[j - 1] * rb.Dis;
    appendTriplets(E, 1.0, largeOffset, offset + (j - 1) * s, triplets, &ifacePos, nullptr);
  }
}

}  // namespace

void NaiveSolver::factor(const std::vector<FastRegion>& regions, const Eigen::SparseMatrix<double>& largeSystem,
                         const RegionPartition& partition, bool damped, IntegratorStats& stats) {
  Stopwatch assembly, factorization;
  assembly.start();
  offsets_.assign(regions.size() + 1, 0);
  int offset = 0;
  for (std::size_t i = 0; i < regions.size(); ++i) {
    offsets_[i] = offset;
    offset += regions[i].ratio * static_cast<int>(regions[i].Mss.rows());
  }
  offsets_.back() = offset;
  const int size = offset + static_cast<int>(largeSystem.rows());
  std::vector<Eigen::Triplet<double>> triplets;
  for (std::size_t i = 0; i < regions.size(); ++i)
    appendRegion(regions[i], offsets_[i], offset, partition.interfacePositions(static_cast<int>(i)), damped, triplets);
  appendTriplets(largeSystem, 1.0, offset, offset, triplets);
  system_.resize(size, size);
  system_.setFromTriplets(triplets.begin(), triplets.end());
  system_.makeCompressed();
  stats.assemblySeconds += assembly.stop();
  factorization.start();
  factorizeCounted(*solver_, system_, analyzed_, stats);
  stats.factorizationSeconds += factorization.stop();
}

void NaiveSolver::solve(std::vector<FastRegion>& regions, const Eigen::VectorXd& largeRhs,
                        Eigen::VectorXd& largeSolution) {
  Eigen::VectorXd rhs(system_.rows());
  for (std::size_t i = 0; i < regions.size(); ++i) {
    const Eigen::MatrixXd& b = regions[i].rhs;
    rhs.segment(offsets_[i], b.size()) = Eigen::Map<const Eigen::VectorXd>(b.data(), b.size());
  }
  rhs.tail(largeRhs.size()) = largeRhs;
  const Eigen::VectorXd solution = solver_->solve(rhs);
  for (std::size_t i = 0; i < regions.size(); ++i) {
    FastRegion& rb = regions[i];
    rb.x = Eigen::Map<const Eigen::MatrixXd>(solution.data() + offsets_[i], rb.rhs.rows(), rb.rhs.cols());
    rb.substituted = true;
  }
  largeSolution = solution.tail(largeRhs.size());
}

}  // namespace asyncfem::detail
