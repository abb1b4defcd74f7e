// SPDX-License-Identifier: BSD-3-Clause
// Small operations on compressed column-major sparse matrices that the asynchronous
// integrator's blocks need. Private to the library.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

namespace asyncfem::detail {

using SparseMatrix = Eigen::SparseMatrix<double>;

/// Appends the entries of block, scaled and shifted by (rowOffset, colOffset), to
/// triplets; with a map, block column c goes to colOffset + columnMap[c] (and likewise rows).
void appendTriplets(const SparseMatrix& block, double scale, int rowOffset, int colOffset,
                    std::vector<Eigen::Triplet<double>>& triplets, const std::vector<int>* rowMap = nullptr,
                    const std::vector<int>* columnMap = nullptr);

/// Address of the stored entry (row, column) of a compressed matrix, or nullptr.
double* findEntry(SparseMatrix& matrix, int row, int column);

/// Column c of a compressed matrix dotted with x (row c of K x when K is symmetric).
double columnDot(const SparseMatrix& matrix, int column, const Eigen::VectorXd& x);

/// Whether x and y are compressed with identical patterns (sizes, column starts and rows).
bool samePattern(const SparseMatrix& x, const SparseMatrix& y);

/// out = a A + b B. When A and B share one pattern (blocks cut from M and K, which the
/// assembler builds on one pattern) only values are written, into out's storage if it
/// already has that pattern; otherwise Eigen's general sum.
void combineInto(double a, const SparseMatrix& A, double b, const SparseMatrix& B, SparseMatrix& out);

/// out = matrix^T for a compressed matrix. The pattern and the entry map are built the
/// first time and whenever matrix's pattern changes (recorded in pattern); after that only
/// values are copied, without an allocation.
struct TransposePattern {
  std::vector<int> outer, inner;  ///< matrix's pattern when the map was built
  std::vector<int> source;        ///< entry k of out is entry source[k] of matrix
};
void transposeInto(const SparseMatrix& matrix, SparseMatrix& out, TransposePattern& pattern);

/// Largest |entry| of a matrix (0 for an empty one).
double largestMagnitude(const SparseMatrix& matrix);

}  // namespace asyncfem::detail
