// SPDX-License-Identifier: BSD-3-Clause
// Small operations on compressed column-major sparse matrices that the asynchronous
// integrator's blocks need. Private to the library.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <utility>
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
/// Returns whether the pattern was new (out laid out afresh).
bool transposeInto(const SparseMatrix& matrix, SparseMatrix& out, TransposePattern& pattern);

/// Largest |entry| of a matrix (0 for an empty one).
double largestMagnitude(const SparseMatrix& matrix);

/// Entries of a compressed matrix changed in place, with their values before.
using KeptEntries = std::vector<std::pair<double*, double>>;

/// matrix(row, column) += value, the entry's value before kept in `kept` (restoreEntries
/// puts it back exactly). Throws asyncfem::Error naming `what` if the entry is not stored.
void addKeepingEntry(SparseMatrix& matrix, int row, int column, double value, KeptEntries& kept, const char* what);

/// Puts every kept entry back (in reverse: an entry changed twice gets its first value) and
/// clears `kept`.
void restoreEntries(KeptEntries& kept);

/// visit(r, c, row, column) for the entries of a vertex's 3 x 3 block whose row and column
/// positions (position[r], position[c]) are both set (>= 0).
template <class Visit>
void forBlockEntries(const std::array<int, 3>& position, Visit&& visit) {
  for (int c = 0; c < 3; ++c) {
    const int column = position[static_cast<std::size_t>(c)];
    if (column < 0) continue;
    for (int r = 0; r < 3; ++r) {
      const int row = position[static_cast<std::size_t>(r)];
      if (row >= 0) visit(r, c, row, column);
    }
  }
}

}  // namespace asyncfem::detail
