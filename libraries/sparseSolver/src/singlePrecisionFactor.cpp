// SPDX-License-Identifier: BSD-3-Clause
#include "detail/singlePrecisionFactor.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace asyncfem::detail {

namespace {

using FloatBlock = Eigen::Map<const Eigen::MatrixXf>;

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
  int widest = 0;
  for (int k = 0; k < supernodes_; ++k) widest = std::max(widest, (pi_[k + 1] - pi_[k]) - (super_[k + 1] - super_[k]));
  work_.resize(size_);
  below_.resize(widest);
}

namespace {

// Supernode k: its first column, column count, the rows below its diagonal block (their
// count and indices) and its dense block (all rows x its columns).
struct Supernode {
  int first;
  int columns;
  int below;
  const int* rowIndex;
  FloatBlock block;
};

}  // namespace

void SinglePrecisionFactor::solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution) {
  const auto supernode = [this](int k) {
    const int first = super_[k];
    const int columns = super_[k + 1] - first;
    const int rowCount = pi_[k + 1] - pi_[k];
    return Supernode{first, columns, rowCount - columns, rows_.data() + pi_[k] + columns,
                     FloatBlock(values_.data() + px_[k], rowCount, columns)};
  };
  // The solve is linear: rhs is scaled to a largest entry of 1 (a power of two, exact) so
  // that it fits float's range whatever its units, and the solution scaled back.
  const double largest = rhs.size() > 0 ? rhs.cwiseAbs().maxCoeff() : 0.0;
  const double scale = largest > 0.0 && std::isfinite(largest) ? std::exp2(std::ceil(std::log2(largest))) : 1.0;
  for (int i = 0; i < size_; ++i) work_[i] = toFloat(rhs[perm_[i]] / scale);
  // Forward: L y = P b, supernode by supernode: the diagonal block's triangle, then the
  // update of the rows below it.
  for (int k = 0; k < supernodes_; ++k) {
    const Supernode node = supernode(k);
    auto y = work_.segment(node.first, node.columns);
    node.block.topRows(node.columns).triangularView<Eigen::Lower>().solveInPlace(y);
    if (node.below == 0) continue;
    auto update = below_.head(node.below);
    update.noalias() = node.block.bottomRows(node.below) * y;
    for (int r = 0; r < node.below; ++r) work_[node.rowIndex[r]] -= update[r];
  }
  // Back: L^T x = y, in reverse.
  for (int k = supernodes_ - 1; k >= 0; --k) {
    const Supernode node = supernode(k);
    auto x = work_.segment(node.first, node.columns);
    if (node.below > 0) {
      auto known = below_.head(node.below);
      for (int r = 0; r < node.below; ++r) known[r] = work_[node.rowIndex[r]];
      x.noalias() -= node.block.bottomRows(node.below).transpose() * known;
    }
    node.block.topRows(node.columns).transpose().triangularView<Eigen::Upper>().solveInPlace(x);
  }
  solution.resize(size_);
  for (int i = 0; i < size_; ++i) solution[perm_[i]] = scale * static_cast<double>(work_[i]);
}

}  // namespace asyncfem::detail
