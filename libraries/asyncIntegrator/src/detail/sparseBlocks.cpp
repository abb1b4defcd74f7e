// SPDX-License-Identifier: BSD-3-Clause
#include "detail/sparseBlocks.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <cmath>
#include <string>

namespace asyncfem::detail {

void appendTriplets(const SparseMatrix& block, double scale, int rowOffset, int colOffset,
                    std::vector<Eigen::Triplet<double>>& triplets, const std::vector<int>* rowMap,
                    const std::vector<int>* columnMap) {
  for (int c = 0; c < block.outerSize(); ++c) {
    for (SparseMatrix::InnerIterator it(block, c); it; ++it) {
      const int row = rowMap ? (*rowMap)[static_cast<std::size_t>(it.row())] : static_cast<int>(it.row());
      const int col = columnMap ? (*columnMap)[static_cast<std::size_t>(c)] : c;
      triplets.emplace_back(rowOffset + row, colOffset + col, scale * it.value());
    }
  }
}

double* findEntry(SparseMatrix& matrix, int row, int column) {
  const int* begin = matrix.innerIndexPtr() + matrix.outerIndexPtr()[column];
  const int* end = matrix.innerIndexPtr() + matrix.outerIndexPtr()[column + 1];
  const int* it = std::lower_bound(begin, end, row);
  if (it == end || *it != row) return nullptr;
  return matrix.valuePtr() + (it - matrix.innerIndexPtr());
}

double columnDot(const SparseMatrix& matrix, int column, const Eigen::VectorXd& x) {
  const int* inner = matrix.innerIndexPtr();
  const double* values = matrix.valuePtr();
  double sum = 0.0;
  for (int k = matrix.outerIndexPtr()[column]; k < matrix.outerIndexPtr()[column + 1]; ++k)
    sum += values[k] * x[inner[k]];
  return sum;
}

bool samePattern(const SparseMatrix& x, const SparseMatrix& y) {
  return x.rows() == y.rows() && x.cols() == y.cols() && x.isCompressed() && y.isCompressed() &&
         x.nonZeros() == y.nonZeros() &&
         std::equal(x.outerIndexPtr(), x.outerIndexPtr() + x.outerSize() + 1, y.outerIndexPtr()) &&
         std::equal(x.innerIndexPtr(), x.innerIndexPtr() + x.nonZeros(), y.innerIndexPtr());
}

void combineInto(double a, const SparseMatrix& A, double b, const SparseMatrix& B, SparseMatrix& out) {
  if (!samePattern(A, B)) {
    out = a * A + b * B;
    out.makeCompressed();
    return;
  }
  if (!samePattern(out, A)) out = A;
  const double* av = A.valuePtr();
  const double* bv = B.valuePtr();
  double* ov = out.valuePtr();
  for (Eigen::Index k = 0; k < A.nonZeros(); ++k) ov[k] = a * av[k] + b * bv[k];
}

bool transposeInto(const SparseMatrix& matrix, SparseMatrix& out, TransposePattern& pattern) {
  const int* outer = matrix.outerIndexPtr();
  const int* inner = matrix.innerIndexPtr();
  const auto columns = static_cast<std::size_t>(matrix.outerSize());
  const auto entries = static_cast<std::size_t>(matrix.nonZeros());
  const bool known = pattern.outer.size() == columns + 1 && pattern.inner.size() == entries &&
                     std::equal(outer, outer + columns + 1, pattern.outer.begin()) &&
                     std::equal(inner, inner + entries, pattern.inner.begin());
  if (!known) {
    out = matrix.transpose();
    out.makeCompressed();
    pattern.outer.assign(outer, outer + columns + 1);
    pattern.inner.assign(inner, inner + entries);
    // Column c's entries, in order, land in out's columns (their rows) in order of c.
    std::vector<int> next(out.outerIndexPtr(), out.outerIndexPtr() + out.outerSize());
    pattern.source.assign(entries, 0);
    for (std::size_t c = 0; c < columns; ++c)
      for (int k = outer[c]; k < outer[c + 1]; ++k) pattern.source[static_cast<std::size_t>(next[inner[k]]++)] = k;
    return true;
  }
  const double* values = matrix.valuePtr();
  double* target = out.valuePtr();
  for (std::size_t k = 0; k < entries; ++k) target[k] = values[pattern.source[k]];
  return false;
}

double largestMagnitude(const SparseMatrix& matrix) {
  double value = 0.0;
  for (Eigen::Index k = 0; k < matrix.nonZeros(); ++k) value = std::max(value, std::abs(matrix.valuePtr()[k]));
  return value;
}

void addKeepingEntry(SparseMatrix& matrix, int row, int column, double value, KeptEntries& kept, const char* what) {
  double* entry = findEntry(matrix, row, column);
  if (entry == nullptr) {
    throw Error(std::string("async integrator: entry (") + std::to_string(row) + ", " + std::to_string(column) +
                ") of " + what + " is not in its pattern");
  }
  kept.emplace_back(entry, *entry);
  *entry += value;
}

void restoreEntries(KeptEntries& kept) {
  for (auto it = kept.rbegin(); it != kept.rend(); ++it) *it->first = it->second;
  kept.clear();
}

}  // namespace asyncfem::detail
