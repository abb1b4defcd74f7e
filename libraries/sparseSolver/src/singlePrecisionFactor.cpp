// SPDX-License-Identifier: BSD-3-Clause
#include "detail/singlePrecisionFactor.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace asyncfem::detail {

namespace {

std::vector<int> copyInts(const int* data, int count) { return std::vector<int>(data, data + count); }

// A double rounded to float; beyond float's range, the infinity of its sign (a plain
// conversion of such a value is undefined behaviour).
float toFloat(double value) {
  if (std::abs(value) > static_cast<double>(std::numeric_limits<float>::max())) {
    const float infinity = std::numeric_limits<float>::infinity();
    return value > 0.0 ? infinity : -infinity;
  }
  return static_cast<float>(value);
}

}  // namespace

void SinglePrecisionFactor::assign(const SupernodalFactorView& factor) {
  size_ = factor.size;
  supernodes_ = factor.supernodes;
  super_ = copyInts(factor.super, supernodes_ + 1);
  pi_ = copyInts(factor.pi, supernodes_ + 1);
  px_ = copyInts(factor.px, supernodes_ + 1);
  rows_ = copyInts(factor.rows, pi_.back());
  perm_ = copyInts(factor.perm, size_);
  values_.resize(static_cast<std::size_t>(px_.back()));
  std::transform(factor.values, factor.values + px_.back(), values_.begin(), toFloat);
  work_.resize(size_);
  below_.resize(widestUpdate(factor));
}

void SinglePrecisionFactor::solve(const Eigen::Ref<const Eigen::VectorXd>& rhs, Eigen::VectorXd& solution) {
  SupernodalArrays<float> factor;
  factor.size = size_;
  factor.supernodes = supernodes_;
  factor.super = super_.data();
  factor.pi = pi_.data();
  factor.px = px_.data();
  factor.rows = rows_.data();
  factor.values = values_.data();
  // The solve is linear: rhs is scaled to a largest entry of 1 (a power of two, exact) so
  // that it fits float's range whatever its units, and the solution scaled back.
  const double largest = rhs.size() > 0 ? rhs.cwiseAbs().maxCoeff() : 0.0;
  const double scale = largest > 0.0 && std::isfinite(largest) ? std::exp2(std::ceil(std::log2(largest))) : 1.0;
  for (int i = 0; i < size_; ++i) work_[i] = toFloat(rhs[perm_[i]] / scale);
  substituteInPlace(factor, work_, below_);
  solution.resize(size_);
  for (int i = 0; i < size_; ++i) solution[perm_[i]] = scale * static_cast<double>(work_[i]);
}

bool SinglePrecisionFactor::agreesWith(
    const std::function<void(const Eigen::VectorXd&, Eigen::VectorXd&)>& exactSolve) {
  // Rounded to float, L's entries carry a relative error of 6e-8 (a solve of the
  // well-conditioned test systems and the shipped scenes' matrices is within 1e-6 of
  // the double factor's), unless they leave float's range (1e-38 to 3e38) or A's
  // conditioning amplifies the rounding: where the copy's solve of a fixed vector is off
  // from the double factor's by more than kLimit (or not finite), it would slow the
  // iterations it preconditions down, and the double factor should precondition instead.
  constexpr double kLimit = 1e-2;
  const Eigen::VectorXd probe = Eigen::VectorXd::LinSpaced(size_, 1.0, 2.0).array().sin();
  Eigen::VectorXd single;
  Eigen::VectorXd exact;
  solve(probe, single);
  exactSolve(probe, exact);
  return (single - exact).norm() <= kLimit * exact.norm();
}

}  // namespace asyncfem::detail
