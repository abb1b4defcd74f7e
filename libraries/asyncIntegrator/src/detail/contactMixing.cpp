// SPDX-License-Identifier: BSD-3-Clause
// The Anderson mixing of the contact iteration's solves (docs/asynchronous-integrator.md,
// "Implicit contact", Eq. C5).
#include <Eigen/QR>

#include "detail/contactIteration.hpp"

namespace asyncfem::detail {

namespace {

/// L's vector, then each region's matrix column by column, as one vector.
template <class Region>
void pack(const Eigen::VectorXd& large, std::size_t count, Region&& region, Eigen::VectorXd& out) {
  Eigen::Index size = large.size();
  for (std::size_t i = 0; i < count; ++i) size += region(i).size();
  out.resize(size);
  out.head(large.size()) = large;
  Eigen::Index at = large.size();
  for (std::size_t i = 0; i < count; ++i) {
    const Eigen::MatrixXd& values = region(i);
    out.segment(at, values.size()) = values.reshaped();
    at += values.size();
  }
}

/// The inverse of pack (the matrices keep their shapes).
template <class Region>
void unpack(const Eigen::VectorXd& in, Eigen::VectorXd& large, std::size_t count, Region&& region) {
  large = in.head(large.size());
  Eigen::Index at = large.size();
  for (std::size_t i = 0; i < count; ++i) {
    Eigen::MatrixXd& values = region(i);
    values.reshaped() = in.segment(at, values.size());
    at += values.size();
  }
}

}  // namespace

void ContactIteration::forgetMixing() {
  mixStates_.clear();
  mixOperators_.clear();
  mixSteps_.clear();
}

// Eq. (C5): with d_j = z_solve,j - z_j the step of solve j from the state it started at,
// gamma minimizes |d_k - sum_j gamma_j (d_{j+1} - d_j)|_2 and the combination is
// z_solve,k - sum_j gamma_j (z_solve,j+1 - z_solve,j) (A_0 z - base alike: it is affine).
bool ContactIteration::mix(Eigen::VectorXd& Y, std::vector<FastRegion>& regions) {
  const std::size_t count = regions.size();
  const auto solvedX = [&](std::size_t i) -> Eigen::MatrixXd& { return regions[i].x; };
  const auto solvedS = [&](std::size_t i) -> Eigen::MatrixXd& { return solvedOperatorS_[i]; };
  if (mixSteps_.size() > static_cast<std::size_t>(kMixingDepth)) {
    mixStates_.erase(mixStates_.begin());
    mixOperators_.erase(mixOperators_.begin());
    mixSteps_.erase(mixSteps_.begin());
  }
  mixStates_.emplace_back();
  mixOperators_.emplace_back();
  pack(Y, count, solvedX, mixStates_.back());
  pack(solvedOperatorL_, count, solvedS, mixOperators_.back());
  pack(
      acceptedY_, count, [&](std::size_t i) -> const Eigen::MatrixXd& { return acceptedX_[i]; }, packed_);
  mixSteps_.push_back(mixStates_.back() - packed_);
  const std::size_t n = mixSteps_.size();
  if (n < 2) return false;
  Eigen::MatrixXd differences(mixSteps_.back().size(), static_cast<Eigen::Index>(n - 1));
  for (std::size_t j = 0; j + 1 < n; ++j)
    differences.col(static_cast<Eigen::Index>(j)) = mixSteps_[j + 1] - mixSteps_[j];
  const Eigen::VectorXd gamma = differences.colPivHouseholderQr().solve(mixSteps_.back());
  if (!gamma.allFinite()) return false;
  packed_ = mixStates_.back();
  Eigen::VectorXd mixedOperator = mixOperators_.back();
  for (std::size_t j = 0; j + 1 < n; ++j) {
    const double g = gamma[static_cast<Eigen::Index>(j)];
    packed_ -= g * (mixStates_[j + 1] - mixStates_[j]);
    mixedOperator -= g * (mixOperators_[j + 1] - mixOperators_[j]);
  }
  unpack(packed_, Y, count, solvedX);
  unpack(mixedOperator, solvedOperatorL_, count, solvedS);
  return true;
}

// Back to the last solve's own state; the older solves are dropped (their combination did
// not lower the residual).
void ContactIteration::unmix(Eigen::VectorXd& Y, std::vector<FastRegion>& regions) {
  const std::size_t count = regions.size();
  unpack(mixStates_.back(), Y, count, [&](std::size_t i) -> Eigen::MatrixXd& { return regions[i].x; });
  unpack(mixOperators_.back(), solvedOperatorL_, count,
         [&](std::size_t i) -> Eigen::MatrixXd& { return solvedOperatorS_[i]; });
  mixStates_.erase(mixStates_.begin(), mixStates_.end() - 1);
  mixOperators_.erase(mixOperators_.begin(), mixOperators_.end() - 1);
  mixSteps_.erase(mixSteps_.begin(), mixSteps_.end() - 1);
}

}  // namespace asyncfem::detail
