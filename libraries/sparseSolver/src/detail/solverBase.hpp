// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <memory>
#include <string>
#include <vector>

namespace asyncfem::detail {

using SparseMatrix = Eigen::SparseMatrix<double>;

/// The pattern (size and index arrays) a solver was analysed with, kept so that
/// factorize() can reject a matrix with another pattern instead of producing garbage.
struct PatternSignature {
  Eigen::Index rows = -1;
  std::vector<int> outer, inner;

  void record(const SparseMatrix& a) {
    rows = a.rows();
    outer.assign(a.outerIndexPtr(), a.outerIndexPtr() + a.outerSize() + 1);
    inner.assign(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros());
  }
  bool analysed() const { return rows >= 0; }
  bool matches(const SparseMatrix& a) const {
    return a.rows() == rows && a.cols() == rows && static_cast<std::size_t>(a.nonZeros()) == inner.size() &&
           std::equal(outer.begin(), outer.end(), a.outerIndexPtr()) &&
           std::equal(inner.begin(), inner.end(), a.innerIndexPtr());
  }
};

/// Argument checks and bookkeeping shared by every backend: square compressed input,
/// the analysed pattern, factorize-before-solve, right-hand-side size.
class SolverBase : public SparseSolver {
 protected:
  /// Throws asyncfem::Error unless `a` is square and compressed.
  static void requireSquareCompressed(const SparseMatrix& a, const std::string& who) {
    if (a.rows() != a.cols()) {
      throw Error(who + ": matrix is " + std::to_string(a.rows()) + " x " + std::to_string(a.cols()) + ", not square");
    }
    if (!a.isCompressed()) throw Error(who + ": matrix must be compressed (call makeCompressed() first)");
  }
  void beginAnalyze(const SparseMatrix& a, const std::string& who) {
    requireSquareCompressed(a, who);
    factored_ = false;
    signature_.record(a);
  }
  void beginFactorize(const SparseMatrix& a, const std::string& who) {
    requireSquareCompressed(a, who);
    if (!signature_.analysed()) throw Error(who + ": factorize() called before analyzePattern()");
    if (!signature_.matches(a)) {
      throw Error(who + ": the matrix pattern (" + std::to_string(a.rows()) + " x " + std::to_string(a.cols()) + ", " +
                  std::to_string(a.nonZeros()) + " non-zeros) differs from the analysed one (" +
                  std::to_string(signature_.rows) + " x " + std::to_string(signature_.rows) + ", " +
                  std::to_string(signature_.inner.size()) +
                  " non-zeros or other indices); call analyzePattern() "
                  "again");
    }
    // A failed factorization leaves no usable factor behind.
    factored_ = false;
  }
  void beginSolve(const Eigen::Ref<const Eigen::MatrixXd>& rhs, const std::string& who) const {
    if (!factored_) throw Error(who + ": solve() called before a successful factorize()");
    if (rhs.rows() != signature_.rows) {
      throw Error(who + ": right-hand side has " + std::to_string(rhs.rows()) + " rows, the matrix has " +
                  std::to_string(signature_.rows) + " rows");
    }
  }
  /// Ends a successful factorize() timed by watch: the factor is usable; counts the
  /// factorization and its seconds.
  void endFactorize(Stopwatch& watch) {
    factored_ = true;
    ++stats_.factorizations;
    stats_.factorSeconds += watch.stop();
  }
  /// Ends a successful solve() of `columns` right-hand sides timed by watch: counts them
  /// and its seconds.
  void endSolve(Eigen::Index columns, Stopwatch& watch) {
    stats_.solvedRightHandSides += columns;
    stats_.solveSeconds += watch.stop();
  }

  PatternSignature signature_;
  bool factored_ = false;
};

/// Backend factories, one per source file.
std::unique_ptr<SparseSolver> makeCholmodSolver(FillOrdering ordering);
std::unique_ptr<SparseSolver> makeUmfpackSolver();
std::unique_ptr<SparseSolver> makeEigenLDLTSolver();
std::unique_ptr<SparseSolver> makeEigenLUSolver();
std::unique_ptr<SparseSolver> makeDenseSolver();

}  // namespace asyncfem::detail
