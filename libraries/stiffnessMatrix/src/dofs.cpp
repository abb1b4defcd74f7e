// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <string>

#include "detail/sizeIndex.hpp"

namespace asyncfem {

namespace {

using detail::Index;
using detail::toIndex;

// Throws ValidationError unless indices is strictly ascending within [0, size).
void checkIndexList(const std::vector<int>& indices, Eigen::Index size, const char* what) {
  for (std::size_t k = 0; k < indices.size(); ++k) {
    const int index = indices[k];
    if (index < 0 || index >= size) {
      throw ValidationError(std::string("SubmatrixExtractor: ") + what + " index " + std::to_string(index) +
                            " (entry " + std::to_string(k) + ") is out of range [0, " + std::to_string(size) + ")");
    }
    if (k > 0 && index <= indices[k - 1]) {
      throw ValidationError(std::string("SubmatrixExtractor: ") + what + " indices must be strictly ascending, but " +
                            std::to_string(index) + " (entry " + std::to_string(k) + ") follows " +
                            std::to_string(indices[k - 1]));
    }
  }
}

// End of column c's stored entries in valuePtr() order (also for an uncompressed matrix).
inline int columnEnd(const Eigen::SparseMatrix<double>& matrix, int c) {
  const int* innerNonZeros = matrix.innerNonZeroPtr();  // null when compressed
  return innerNonZeros != nullptr ? matrix.outerIndexPtr()[c] + innerNonZeros[c] : matrix.outerIndexPtr()[c + 1];
}

// Row map of a submatrix: entry r is the position of full row r in rows, -1 where r is
// not kept.
std::vector<int> subRowMap(const std::vector<int>& rows, Eigen::Index fullRows) {
  std::vector<int> fullToSubRow(toIndex(static_cast<int>(fullRows)), -1);
  for (std::size_t k = 0; k < rows.size(); ++k) fullToSubRow[toIndex(rows[k])] = static_cast<int>(k);
  return fullToSubRow;
}

}  // namespace

FreeDofs::FreeDofs(int numDofs, const std::vector<int>& fixedDofs) {
  if (numDofs < 0) throw ValidationError("FreeDofs: negative number of DOFs " + std::to_string(numDofs));
  fullToFree_.assign(toIndex(numDofs), 0);
  for (int dof : fixedDofs) {
    if (dof < 0 || dof >= numDofs) {
      throw ValidationError("FreeDofs: fixed DOF " + std::to_string(dof) + " (vertex " +
                            std::to_string(dof >= 0 ? dof / 3 : -1) + ") is out of range [0, " +
                            std::to_string(numDofs) + ")");
    }
    fullToFree_[toIndex(dof)] = -1;
  }
  for (int dof = 0; dof < numDofs; ++dof) {
    if (fullToFree_[toIndex(dof)] < 0) continue;
    fullToFree_[toIndex(dof)] = static_cast<int>(freeToFull_.size());
    freeToFull_.push_back(dof);
  }
}

FreeDofs FreeDofs::fromFixedVertices(int numVertices, const std::vector<int>& fixedVertices) {
  if (numVertices < 0) throw ValidationError("FreeDofs: negative number of vertices " + std::to_string(numVertices));
  std::vector<int> fixedDofs;
  fixedDofs.reserve(3 * fixedVertices.size());
  for (int vertex : fixedVertices) {
    if (vertex < 0 || vertex >= numVertices) {
      throw ValidationError("FreeDofs: fixed vertex " + std::to_string(vertex) + " is out of range [0, " +
                            std::to_string(numVertices) + ")");
    }
    for (int c = 0; c < 3; ++c) fixedDofs.push_back((3 * vertex) + c);
  }
  return FreeDofs(3 * numVertices, fixedDofs);
}

Eigen::VectorXd FreeDofs::restrict(const Eigen::VectorXd& full) const {
  if (full.size() != numDofs()) {
    throw Error("FreeDofs::restrict: vector has " + std::to_string(full.size()) + " entries, expected " +
                std::to_string(numDofs()));
  }
  Eigen::VectorXd result(numFree());
  for (int k = 0; k < numFree(); ++k) result[k] = full[freeToFull_[toIndex(k)]];
  return result;
}

Eigen::VectorXd FreeDofs::expand(const Eigen::VectorXd& free) const {
  if (free.size() != numFree()) {
    throw Error("FreeDofs::expand: vector has " + std::to_string(free.size()) + " entries, expected " +
                std::to_string(numFree()));
  }
  Eigen::VectorXd result = Eigen::VectorXd::Zero(numDofs());
  for (int k = 0; k < numFree(); ++k) result[freeToFull_[toIndex(k)]] = free[k];
  return result;
}

SubmatrixExtractor::SubmatrixExtractor(const Eigen::SparseMatrix<double>& full, const std::vector<int>& rows,
                                       const std::vector<int>& cols) {
  rebuild(full, rows, cols);
}

void SubmatrixExtractor::rebuild(const Eigen::SparseMatrix<double>& full, const std::vector<int>& rows,
                                 const std::vector<int>& cols) {
  checkIndexList(rows, full.rows(), "row");
  checkIndexList(cols, full.cols(), "column");
  const std::vector<int> fullToSubRow = subRowMap(rows, full.rows());
  const int numSubCols = static_cast<int>(cols.size());
  const int* outer = full.outerIndexPtr();
  const int* inner = full.innerIndexPtr();

  // One pass into room for every entry of the kept columns (a bound, trimmed after). Rows
  // of full are sorted and the row map is increasing, so sub's rows come out sorted.
  long long bound = 0;
  for (int c : cols) bound += columnEnd(full, c) - outer[c];
  pattern_.resize(static_cast<Eigen::Index>(rows.size()), numSubCols);
  pattern_.resizeNonZeros(static_cast<Eigen::Index>(bound));
  sourceSlots_.resize(static_cast<std::size_t>(bound));
  int* subOuter = pattern_.outerIndexPtr();
  int* subInner = pattern_.innerIndexPtr();
  int* slots = sourceSlots_.data();
  int written = 0;
  for (int j = 0; j < numSubCols; ++j) {
    subOuter[j] = written;
    const int c = cols[toIndex(j)];
    for (int p = outer[c]; p < columnEnd(full, c); ++p) {
      const int subRow = fullToSubRow[toIndex(inner[p])];
      subInner[written] = subRow;
      slots[written] = p;
      written += subRow >= 0 ? 1 : 0;
    }
  }
  subOuter[numSubCols] = written;
  pattern_.resizeNonZeros(written);
  sourceSlots_.resize(static_cast<std::size_t>(written));
  std::fill_n(pattern_.valuePtr(), written, 0.0);
  sourceRows_ = full.rows();
  sourceCols_ = full.cols();
  sourceNonZeros_ = full.nonZeros();
}

Eigen::SparseMatrix<double> SubmatrixExtractor::extract(const Eigen::SparseMatrix<double>& full) const {
  Eigen::SparseMatrix<double> sub = pattern_;
  update(full, sub);
  return sub;
}

Eigen::SparseMatrix<double> SubmatrixExtractor::extractCombination(double a, const Eigen::SparseMatrix<double>& A,
                                                                   double b,
                                                                   const Eigen::SparseMatrix<double>& B) const {
  // The pattern without its zero values: updateCombination writes every value.
  Eigen::SparseMatrix<double> sub;
  extractCombinationInto(a, A, b, B, sub);
  return sub;
}

void SubmatrixExtractor::extractCombinationInto(double a, const Eigen::SparseMatrix<double>& A, double b,
                                                const Eigen::SparseMatrix<double>& B,
                                                Eigen::SparseMatrix<double>& sub) const {
  // The pattern without its zero values: updateCombination writes every value. Eigen's
  // resize keeps the entry storage (and the column starts when their count is unchanged).
  sub.resize(pattern_.rows(), pattern_.cols());
  sub.resizeNonZeros(pattern_.nonZeros());
  std::copy_n(pattern_.outerIndexPtr(), pattern_.outerSize() + 1, sub.outerIndexPtr());
  std::copy_n(pattern_.innerIndexPtr(), pattern_.nonZeros(), sub.innerIndexPtr());
  updateCombination(a, A, b, B, sub);
}

void SubmatrixExtractor::checkShapes(const Eigen::SparseMatrix<double>& full, const Eigen::SparseMatrix<double>& sub,
                                     const char* caller) const {
  if (full.rows() != sourceRows_ || full.cols() != sourceCols_ || full.nonZeros() != sourceNonZeros_) {
    throw Error(std::string("SubmatrixExtractor::") + caller + ": the " + std::to_string(full.rows()) + " x " +
                std::to_string(full.cols()) + " matrix with " + std::to_string(full.nonZeros()) +
                " entries does not have the pattern the extractor was built for (" + std::to_string(sourceRows_) +
                " x " + std::to_string(sourceCols_) + ", " + std::to_string(sourceNonZeros_) + " entries)");
  }
  if (sub.rows() != pattern_.rows() || sub.cols() != pattern_.cols() || sub.nonZeros() != pattern_.nonZeros() ||
      !sub.isCompressed()) {
    throw Error(std::string("SubmatrixExtractor::") + caller + ": sub is not a matrix from extract() (" +
                std::to_string(sub.rows()) + " x " + std::to_string(sub.cols()) + ", expected " +
                std::to_string(pattern_.rows()) + " x " + std::to_string(pattern_.cols()) + ")");
  }
}

void SubmatrixExtractor::update(const Eigen::SparseMatrix<double>& full, Eigen::SparseMatrix<double>& sub) const {
  checkShapes(full, sub, "update");
  const double* source = full.valuePtr();
  double* target = sub.valuePtr();
  const Eigen::Index count = pattern_.nonZeros();
#pragma omp parallel for schedule(static)
  for (Eigen::Index k = 0; k < count; ++k) target[k] = source[sourceSlots_[static_cast<std::size_t>(k)]];
}

void SubmatrixExtractor::updateCombination(double a, const Eigen::SparseMatrix<double>& A, double b,
                                           const Eigen::SparseMatrix<double>& B,
                                           Eigen::SparseMatrix<double>& sub) const {
  checkShapes(A, sub, "updateCombination");
  checkShapes(B, sub, "updateCombination");
  const double* first = A.valuePtr();
  const double* second = B.valuePtr();
  double* target = sub.valuePtr();
  const Eigen::Index count = pattern_.nonZeros();
#pragma omp parallel for schedule(static)
  for (Eigen::Index k = 0; k < count; ++k) {
    const std::size_t slot = static_cast<std::size_t>(sourceSlots_[static_cast<std::size_t>(k)]);
    target[k] = (a * first[slot]) + (b * second[slot]);
  }
}

}  // namespace asyncfem
