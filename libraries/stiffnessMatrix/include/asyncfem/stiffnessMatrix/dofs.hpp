// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

namespace asyncfem {

/// Splits the 3n DOFs into fixed and free ones and moves vectors between the full
/// (3n) and free (numFree) numbering. Fixed DOFs are removed from systems, never
/// penalised.
class FreeDofs {
 public:
  FreeDofs() = default;
  /// fixedDofs: global DOF ids (any order, duplicates allowed), each in [0, numDofs);
  /// throws ValidationError naming the first DOF out of range.
  FreeDofs(int numDofs, const std::vector<int>& fixedDofs);
  /// All three DOFs of each listed vertex are fixed; throws ValidationError naming a
  /// vertex out of [0, numVertices).
  static FreeDofs fromFixedVertices(int numVertices, const std::vector<int>& fixedVertices);

  int numDofs() const { return static_cast<int>(fullToFree_.size()); }
  int numFree() const { return static_cast<int>(freeToFull_.size()); }
  int numFixed() const { return numDofs() - numFree(); }
  /// free index -> global DOF (ascending).
  const std::vector<int>& freeToFull() const { return freeToFull_; }
  /// global DOF -> free index, -1 if fixed.
  const std::vector<int>& fullToFree() const { return fullToFree_; }
  bool isFixed(int dof) const { return fullToFree_[static_cast<std::size_t>(dof)] < 0; }

  /// The free entries of a full vector (size numDofs -> numFree); asyncfem::Error on a
  /// size mismatch.
  Eigen::VectorXd restrict(const Eigen::VectorXd& full) const;
  /// A full vector with the free entries from free and the fixed entries zero
  /// (numFree -> numDofs); asyncfem::Error on a size mismatch.
  Eigen::VectorXd expand(const Eigen::VectorXd& free) const;

 private:
  std::vector<int> freeToFull_;
  std::vector<int> fullToFree_;
};

/// Extracts the submatrix A(rows, cols) of a sparse matrix, building its pattern and a
/// value map once, so that later calls to update() with a matrix of the same pattern
/// copy values only (one pass, no search). rows and cols are ascending index lists.
/// Used to remove fixed DOFs (rows = cols = free DOFs) and to cut the asynchronous
/// integrator's blocks (K^{SS}, K^{SL}, ...).
class SubmatrixExtractor {
 public:
  SubmatrixExtractor() = default;
  /// Builds the pattern of full(rows, cols) (rows.size() x cols.size()) and the value
  /// map. Throws ValidationError if an index list is not strictly ascending or leaves
  /// [0, full.rows()) resp. [0, full.cols()). full may be uncompressed.
  SubmatrixExtractor(const Eigen::SparseMatrix<double>& full, const std::vector<int>& rows,
                     const std::vector<int>& cols);
  /// The constructor's work for new index lists, in the storage this extractor already
  /// holds: nothing is allocated (nor freed) when the new submatrix keeps at most as many
  /// entries. A re-partition cuts L's block this way: a fresh map of a block of millions of
  /// entries cost 25-45 ms of page faults on the 10k-vertex dragon, about 3 of its
  /// single-rate steps. Same checks and errors as the constructor.
  void rebuild(const Eigen::SparseMatrix<double>& full, const std::vector<int>& rows, const std::vector<int>& cols);

  /// A new submatrix with values from full.
  Eigen::SparseMatrix<double> extract(const Eigen::SparseMatrix<double>& full) const;
  /// Overwrites sub's values (sub from extract()) with those of full, which must have
  /// the pattern the extractor was built from (size and entry count are checked:
  /// asyncfem::Error otherwise). Parallel, one copy per stored entry.
  void update(const Eigen::SparseMatrix<double>& full, Eigen::SparseMatrix<double>& sub) const;
  /// Overwrites sub's values (sub from extract()) with those of a A + b B, where A and B
  /// both have the pattern the extractor was built from (checked as in update()): one pass
  /// instead of two extractions and a sum, e.g. M + h^2 K on a block of one mesh.
  void updateCombination(double a, const Eigen::SparseMatrix<double>& A, double b, const Eigen::SparseMatrix<double>& B,
                         Eigen::SparseMatrix<double>& sub) const;
  /// A new submatrix with values a A + b B: extract() and updateCombination() in one pass
  /// over the values (a large block cut once per partition).
  Eigen::SparseMatrix<double> extractCombination(double a, const Eigen::SparseMatrix<double>& A, double b,
                                                 const Eigen::SparseMatrix<double>& B) const;
  /// extractCombination() into sub, whatever its shape before, reusing its storage where it
  /// is large enough (rebuild()'s companion).
  void extractCombinationInto(double a, const Eigen::SparseMatrix<double>& A, double b,
                              const Eigen::SparseMatrix<double>& B, Eigen::SparseMatrix<double>& sub) const;

 private:
  // Throws asyncfem::Error (naming caller) unless full has the source pattern's shape and
  // entry count and sub is one of extract()'s matrices.
  void checkShapes(const Eigen::SparseMatrix<double>& full, const Eigen::SparseMatrix<double>& sub,
                   const char* caller) const;

  Eigen::SparseMatrix<double> pattern_;
  std::vector<int> sourceSlots_;  // for every stored entry of pattern_, its index in full.valuePtr()
  // Shape and entry count of the matrix the map was built from (cheap pattern check).
  Eigen::Index sourceRows_ = 0;
  Eigen::Index sourceCols_ = 0;
  Eigen::Index sourceNonZeros_ = 0;
};

}  // namespace asyncfem
