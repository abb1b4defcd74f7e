// SPDX-License-Identifier: BSD-3-Clause
// H^{LL*} (Eq. A13 of docs/asynchronous-integrator.md): factor, solve, lagged refinement.
#include "detail/schurSolver.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <cmath>

#include "detail/multirateSupport.hpp"
#include "detail/sparseBlocks.hpp"

namespace asyncfem::detail {

namespace {
/// Largest W = (A^L)^{-1} U (doubles) the low-rank Schur form stores: 64M = 512 MiB.
constexpr double kMaxLowRankEntries = 64.0 * 1024 * 1024;

/// Positions (inside L) of the interface DOFs of every region, sorted and unique.
std::vector<int> interfaceUnionOf(const RegionPartition& partition) {
  std::vector<int> all;
  for (int i = 0; i < partition.numRegions(); ++i) {
    const std::vector<int>& pos = partition.interfacePositions(i);
    all.insert(all.end(), pos.begin(), pos.end());
  }
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  return all;
}
}  // namespace

void ColumnStore::shape(Eigen::Index rows, Eigen::Index columns, Eigen::Index kept) {
  const auto needed = static_cast<std::size_t>(rows) * static_cast<std::size_t>(columns);
  if (needed > capacity_) {
    // A quarter more than asked: the next partition's interface is often a little larger.
    // Pages untouched until written cost nothing.
    const std::size_t capacity = needed + needed / 4;
    std::unique_ptr<double[]> grown(new double[capacity]);
    if (rows == rows_ && kept > 0) std::copy_n(data_.get(), static_cast<std::size_t>(rows * kept), grown.get());
    data_ = std::move(grown);
    capacity_ = capacity;
  }
  rows_ = rows;
  columns_ = columns;
}

void ColumnStore::release() {
  data_.reset();
  capacity_ = 0;
  rows_ = columns_ = 0;
}

void SchurSolver::reset() {
  auto old = std::make_unique<SchurSolver>(std::move(*this));
  *this = SchurSolver();
  external_ = std::move(old->external_);
  directions_ = std::move(old->directions_);
  productsOfDirections_ = std::move(old->productsOfDirections_);
  // The old factor, pattern and maps (tens of MiB at |L| of 30k) are freed by the next
  // factor(), not here: a quick-set-up partition starts without that cost, and a
  // partition that builds its own factor frees them just before.
  retired_ = old->retired_ ? std::move(old->retired_) : std::move(old);
}

void SchurSolver::useExternalSolver(AsyncOptions::Processes::LargeSystemSolverFactory factory,
                                    std::vector<int> largeDofs, std::vector<std::vector<int>> interfaceDofs) {
  external_ = std::move(factory);
  externalLarge_ = std::move(largeDofs);
  externalInterfaces_ = std::move(interfaceDofs);
  solver_.reset();
  analyzed_ = false;
}

void SchurSolver::chooseSolver(SchurMode mode) {
  if (mode != modeUsed_ || !solver_) {
    if (external_) {
      solver_ = external_(externalLarge_, externalInterfaces_);
      if (!solver_) throw Error("async integrator: the large-system solver factory returned no solver");
    } else {
      solver_ = makeSparseSolver(mode == SchurMode::lu ? SolverKind::umfpack : SolverKind::cholmod);
    }
    analyzed_ = false;
  }
  modeUsed_ = mode;
}

void SchurSolver::factor(const SparseMatrix& largeSystem, const RegionPartition& partition,
                         const std::vector<FastRegion>& regions, SchurMode requested, AsyncCoupling coupling,
                         double asymmetry, IntegratorStats& stats) {
  retired_.reset();
  transform_ = nullptr;
  factored_ = true;
  refreshNext_ = false;
  borrowed_ = nullptr;
  borrowedLarge_.clear();
  kept_ = 0;
  directions_.release();
  productsOfDirections_.release();
  const auto numLarge = static_cast<double>(largeSystem.rows());
  if (largeSystem.rows() == 0) return;
  const std::vector<int> all = interfaceUnionOf(partition);
  SchurMode mode = requested;
  if (mode == SchurMode::lowRank && coupling == AsyncCoupling::stable) {
    // The stable coupling's H^{LL*} is symmetric (to round-off): its own Cholesky factor
    // is exact and costs one sparse solve per step, where the low-rank form adds a dense
    // |L| x q product per step and q solves with A^L per rebuild.
    mode = asymmetry <= 1e-10 ? SchurMode::symmetric : SchurMode::lu;
  }
  if (mode == SchurMode::lowRank && numLarge * static_cast<double>(all.size()) > kMaxLowRankEntries) {
    mode = SchurMode::lu;  // A^{-1} U would not fit: factor H^{LL*} itself
  }
  // An external solver is given H^{LL*} itself, symmetrized (the stable coupling's
  // corrections are symmetric to round-off; the constructor refuses the paper's).
  if (external_) mode = SchurMode::symmetric;
  chooseSolver(mode);
  if (mode == SchurMode::lowRank) {
    factorLowRank(largeSystem, partition, regions, all, stats);
  } else {
    factorAssembled(largeSystem, partition, regions, stats);
  }
}

// H^{LL*} = A^L - U C U^T with U the interface columns and C the sum of the regions'
// corrections. With W = (A^L)^{-1} U: x = y + W C z, y = (A^L)^{-1} b and
// (I - U^T W C) z = U^T y (see solve). A^L is SPD: Cholesky.
void SchurSolver::factorLowRank(const SparseMatrix& largeSystem, const RegionPartition& partition,
                                const std::vector<FastRegion>& regions, const std::vector<int>& all,
                                IntegratorStats& stats) {
  factorizeCounted(*solver_, largeSystem, analyzed_, stats);
  interfaceUnion_ = all;
  const auto q = static_cast<Eigen::Index>(all.size());
  if (q == 0) return;
  const auto numLarge = static_cast<Eigen::Index>(largeSystem.rows());
  std::vector<int> place(static_cast<std::size_t>(numLarge), -1);
  for (Eigen::Index k = 0; k < q; ++k)
    place[static_cast<std::size_t>(all[static_cast<std::size_t>(k)])] = static_cast<int>(k);
  unionCorrection_.setZero(q, q);
  for (int i = 0; i < partition.numRegions(); ++i) {
    const std::vector<int>& pos = partition.interfacePositions(i);
    const Eigen::MatrixXd& c = regions[static_cast<std::size_t>(i)].correction;
    for (std::size_t b = 0; b < pos.size(); ++b)
      for (std::size_t a = 0; a < pos.size(); ++a)
        unionCorrection_(place[static_cast<std::size_t>(pos[a])], place[static_cast<std::size_t>(pos[b])]) +=
            c(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
  }
  Eigen::MatrixXd selector = Eigen::MatrixXd::Zero(numLarge, q);
  for (Eigen::Index k = 0; k < q; ++k) selector(all[static_cast<std::size_t>(k)], k) = 1.0;
  solver_->solve(selector, lowRankBasis_);  // W
  Eigen::MatrixXd interfaceRows(q, q);
  for (Eigen::Index k = 0; k < q; ++k) interfaceRows.row(k) = lowRankBasis_.row(all[static_cast<std::size_t>(k)]);
  capacitance_.compute(Eigen::MatrixXd::Identity(q, q) - interfaceRows * unionCorrection_);
}

// Every block entry is stored, so a refactor writes values only and the analysis is kept.
void SchurSolver::buildPattern(const SparseMatrix& largeSystem, const RegionPartition& partition) {
  const auto numLarge = static_cast<int>(largeSystem.rows());
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(largeSystem.nonZeros()));
  appendTriplets(largeSystem, 1.0, 0, 0, triplets);
  for (int i = 0; i < partition.numRegions(); ++i) {
    const std::vector<int>& pos = partition.interfacePositions(i);
    for (int column : pos)
      for (int row : pos) triplets.emplace_back(row, column, 0.0);
  }
  schur_.resize(numLarge, numLarge);
  schur_.setFromTriplets(triplets.begin(), triplets.end());
  schur_.makeCompressed();
  fromLarge_.resize(static_cast<std::size_t>(largeSystem.nonZeros()));
  for (int c = 0; c < numLarge; ++c)
    for (int k = largeSystem.outerIndexPtr()[c]; k < largeSystem.outerIndexPtr()[c + 1]; ++k)
      fromLarge_[static_cast<std::size_t>(k)] =
          static_cast<int>(findEntry(schur_, largeSystem.innerIndexPtr()[k], c) - schur_.valuePtr());
  fromBlock_.assign(static_cast<std::size_t>(partition.numRegions()), {});
  for (int i = 0; i < partition.numRegions(); ++i) {
    const std::vector<int>& pos = partition.interfacePositions(i);
    std::vector<int>& index = fromBlock_[static_cast<std::size_t>(i)];
    index.reserve(pos.size() * pos.size());
    for (int column : pos)
      for (int row : pos) index.push_back(static_cast<int>(findEntry(schur_, row, column) - schur_.valuePtr()));
  }
  patternBuilt_ = true;
}

// H^{LL*} = A^L - sum_i C_i on the I_i x I_i blocks (their symmetric part in symmetric mode).
void SchurSolver::factorAssembled(const SparseMatrix& largeSystem, const RegionPartition& partition,
                                  const std::vector<FastRegion>& regions, IntegratorStats& stats) {
  Stopwatch assembly;
  if (!patternBuilt_) buildPattern(largeSystem, partition);
  double* values = schur_.valuePtr();
  std::fill(values, values + schur_.nonZeros(), 0.0);
  for (std::size_t k = 0; k < fromLarge_.size(); ++k) values[fromLarge_[k]] += largeSystem.valuePtr()[k];
  for (int i = 0; i < partition.numRegions(); ++i) {
    const Eigen::MatrixXd& c = regions[static_cast<std::size_t>(i)].correction;
    const std::vector<int>& index = fromBlock_[static_cast<std::size_t>(i)];
    const Eigen::Index qi = c.rows();
    for (Eigen::Index b = 0; b < qi; ++b)
      for (Eigen::Index a = 0; a < qi; ++a) {
        const double entry = modeUsed_ == SchurMode::symmetric ? 0.5 * (c(a, b) + c(b, a)) : c(a, b);
        values[index[static_cast<std::size_t>(b * qi + a)]] -= entry;
      }
  }
  stats.assemblySeconds += assembly.stop();
  // An iterative solver preconditions on Â^L, H^{LL*} without the regions' dense blocks.
  if (solver_->usesPreconditionerMatrix()) solver_->setPreconditionerMatrix(largeSystem);
  factorizeCounted(*solver_, schur_, analyzed_, stats);
}

void SchurSolver::borrow(WholeSystemFactor* whole, std::vector<int> largeDofs) {
  borrowed_ = whole;
  borrowedLarge_ = std::move(largeDofs);
}

void SchurSolver::solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution) {
  if (borrowed_ != nullptr) {
    borrowed_->solveOnLarge(borrowedLarge_, rhs, solution);
    return;
  }
  solver_->solve(rhs, solution_);
  solution = solution_.col(0);
  if (modeUsed_ != SchurMode::lowRank || interfaceUnion_.empty()) return;
  const Eigen::VectorXd yInterface = gather(solution, interfaceUnion_);
  const Eigen::VectorXd z = capacitance_.solve(yInterface);
  solution.noalias() += lowRankBasis_ * (unionCorrection_ * z);
}

void SchurSolver::precondition(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution) {
  if (!transform_) {
    applyPreconditioner(rhs, solution);
    return;
  }
  turned_ = rhs;
  transform_(turned_, true);
  applyPreconditioner(turned_, solution);
  transform_(solution, false);
}

void SchurSolver::applyPreconditioner(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution) {
  if (borrowed_ != nullptr || modeUsed_ != SchurMode::symmetric) {
    solve(rhs, solution);
    return;
  }
  solver_->solveApproximately(rhs, solution_);
  solution = solution_.col(0);
}

SchurSolver::Refinement SchurSolver::refine(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution,
                                            const Operator& apply, bool symmetric, int maxIterations, double tolerance,
                                            const Tracker& track) {
  Refinement result;
  const double scale = rhs.norm();
  precondition(rhs, solution);
  if (scale == 0.0) {
    result.converged = result.zeroRightHandSide = true;
    return result;
  }
  apply(solution, product_);
  if (track) track(1.0, true);
  struct Untrack {
    const Tracker*& slot;
    ~Untrack() { slot = nullptr; }
  } untrack{track_};
  track_ = track ? &track : nullptr;
  residual_ = rhs - product_;  // r
  double rz = 0.0;
  for (int iteration = 1; iteration <= maxIterations; ++iteration) {
    result.residual = residual_.norm() / scale;
    if (!std::isfinite(result.residual)) return result;
    if (result.residual <= tolerance) {
      result.converged = true;
      // Slow: the next step refactors.
      refreshNext_ = iteration > maxIterations / 2;
      return result;
    }
    ++result.iterations;
    precondition(residual_, correction_);  // z = P^{-1} r
    if (!symmetric) {
      solution += correction_;
      apply(solution, product_);
      if (track) track(1.0, true);
      residual_ = rhs - product_;
      continue;
    }
    if (!(conjugateStep(solution, apply, iteration == 1, false, rz) > 0.0)) return result;
  }
  return result;
}

// From z = correction_: the new direction p = z + beta p (deflated when asked), H p, and
// the step along it.
double SchurSolver::conjugateStep(Eigen::VectorXd& solution, const Operator& apply, bool first, bool deflated,
                                  double& rz) {
  const double rzNew = residual_.dot(correction_);
  if (first) {
    direction_ = correction_;
  } else {
    // Flexible (Polak-Ribiere) beta = z^T (r - r_previous) / rz: equal to the classical
    // rzNew / rz with a fixed symmetric preconditioner, and robust to one that is only
    // nearly so (the single-precision factor of solveApproximately).
    direction_ = correction_ + ((rzNew - previousResidual_.dot(correction_)) / rz) * direction_;
  }
  previousResidual_ = residual_;
  rz = rzNew;
  if (deflated && kept_ > 0) {
    coefficients_.noalias() = productsOfDirections_.leftCols(kept_).transpose() * direction_;
    direction_.noalias() -= directions_.leftCols(kept_) * coefficients_;
  }
  apply(direction_, product_);
  const double curvature = direction_.dot(product_);
  if (!(curvature > 0.0)) return curvature;
  const double step = rz / curvature;
  solution += step * direction_;
  if (track_ != nullptr) (*track_)(step, false);
  residual_ -= step * product_;
  return curvature;
}

// Deflated preconditioned conjugate gradients (Saad, Yeung, Erhel & Guyomarc'h 2000) with
// W H-orthonormal: x_0 = W W^T b, and every direction p = z + beta p - W (H W)^T z stays
// H-orthogonal to W. The new directions, normalized, join W while there is room.
SchurSolver::Refinement SchurSolver::solveDeflated(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution,
                                                   const Operator& apply, int maxIterations, double tolerance,
                                                   int keep) {
  Refinement result;
  const Eigen::Index n = rhs.size();
  const double scale = rhs.norm();
  solution.setZero(n);
  if (scale == 0.0) {
    result.converged = result.zeroRightHandSide = true;
    return result;
  }
  if (directions_.rows() != n) kept_ = 0;  // another operator's size: nothing to keep
  if (directions_.rows() != n || directions_.columns() < keep) {
    kept_ = std::min(kept_, keep);
    directions_.shape(n, keep, kept_);
    productsOfDirections_.shape(n, keep, kept_);
  }
  residual_ = rhs;
  if (kept_ > 0) {
    coefficients_.noalias() = directions_.leftCols(kept_).transpose() * rhs;
    solution.noalias() = directions_.leftCols(kept_) * coefficients_;
    residual_.noalias() -= productsOfDirections_.leftCols(kept_) * coefficients_;
  }
  double rz = 0.0;
  for (int iteration = 1;; ++iteration) {
    result.residual = residual_.norm() / scale;
    if (!std::isfinite(result.residual)) return result;
    if (result.residual <= tolerance) {
      result.converged = true;
      return result;
    }
    if (iteration > maxIterations) return result;
    ++result.iterations;
    solve(residual_, correction_);  // z = P^{-1} r
    const double curvature = conjugateStep(solution, apply, iteration == 1, true, rz);
    if (!(curvature > 0.0)) return result;
    if (kept_ < keep) {
      const double norm = std::sqrt(curvature);
      directions_.col(kept_) = direction_ / norm;
      productsOfDirections_.col(kept_) = product_ / norm;
      ++kept_;
    }
  }
}

}  // namespace asyncfem::detail
