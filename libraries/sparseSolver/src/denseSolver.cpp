// SPDX-License-Identifier: BSD-3-Clause
// Dense Cholesky (Eigen's blocked LLT) behind SparseSolver, for small SPD systems: below a
// few hundred unknowns a dense factor's vectorized substitutions cost less than a sparse
// factor's indexed ones, however few its non-zeros.
#include <Eigen/Cholesky>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <cmath>
#include <string>

#include "detail/solverBase.hpp"

namespace asyncfem::detail {
namespace {

/// Most unknowns a dense factor may have: 16384^2 doubles are 2 GiB.
constexpr Eigen::Index kMaxDenseUnknowns = 16384;

/// The first column whose pivot is not positive in an unblocked Cholesky of the upper
/// triangle of a (symmetric), or -1. Run only after the blocked factorization failed, to
/// name the column as the sparse kinds do.
Eigen::Index firstBadPivot(Eigen::MatrixXd a) {
  const Eigen::Index n = a.rows();
  for (Eigen::Index k = 0; k < n; ++k) {
    const double pivot = a(k, k) - a.col(k).head(k).squaredNorm();
    if (!(pivot > 0.0) || !std::isfinite(pivot)) return k;
    const double diagonal = std::sqrt(pivot);
    a(k, k) = diagonal;
    // The upper factor R (A = R^T R) overwrites the upper triangle: column j's head holds
    // R(0..k-1, j), so row k of R is one dot product per column.
    for (Eigen::Index j = k + 1; j < n; ++j) a(k, j) = (a(k, j) - a.col(k).head(k).dot(a.col(j).head(k))) / diagonal;
  }
  return -1;
}

class DenseSolver final : public SolverBase {
 public:
  SolverKind kind() const override { return SolverKind::dense; }
  std::string ordering() const override { return signature_.analysed() ? "natural" : "none"; }

  void analyzePattern(const SparseMatrix& a) override {
    Stopwatch watch;  // runs from construction
    requireSquareCompressed(a, "dense");
    if (a.rows() > kMaxDenseUnknowns) {
      throw Error("dense: the matrix has " + std::to_string(a.rows()) +
                  " unknowns; the dense solver holds n^2 doubles " + "and takes at most " +
                  std::to_string(kMaxDenseUnknowns) + " (use cholmod for larger systems)");
    }
    beginAnalyze(a, "dense");
    ++stats_.analyses;
    stats_.analyzeSeconds += watch.stop();
  }

  void factorize(const SparseMatrix& a) override {
    Stopwatch watch;  // runs from construction
    beginFactorize(a, "dense");
    const Eigen::Index n = a.rows();
    // The upper triangle, as the sparse Cholesky kinds read it (LLT<Upper> reads no more).
    dense_.setZero(n, n);
    for (Eigen::Index c = 0; c < a.outerSize(); ++c) {
      for (SparseMatrix::InnerIterator it(a, c); it; ++it) {
        if (it.row() <= c) dense_(it.row(), c) = it.value();
      }
    }
    factor_.compute(dense_);
    if (factor_.info() != Eigen::Success) {
      const Eigen::Index column = firstBadPivot(dense_);
      NumericalErrorLocation location;
      location.dof = static_cast<int>(column);
      throw NumericalError("dense: matrix is not positive definite: non-positive pivot at column " +
                               std::to_string(column) + " (of " + std::to_string(n) + ")",
                           location);
    }
    const double size = static_cast<double>(n);
    stats_.factorNonZeros = static_cast<long long>(n * (n + 1) / 2);
    stats_.factorFlops = size * size * size / 3.0;
    stats_.solveFlopsPerRhs = 4.0 * static_cast<double>(stats_.factorNonZeros);  // 2 n^2 + 2 n
    endFactorize(watch);
  }

  void solve(const Eigen::Ref<const Eigen::MatrixXd>& rhs, Eigen::MatrixXd& solution) override {
    Stopwatch watch;  // runs from construction
    beginSolve(rhs, "dense");
    solution = rhs;
    if (solution.cols() == 1) {
      // One column through the vector kernels: the matrix kernels' blocking and packing
      // cost several times the substitution itself at these sizes.
      Eigen::Map<Eigen::VectorXd> column(solution.data(), solution.rows());
      factor_.solveInPlace(column);
    } else {
      factor_.solveInPlace(solution);
    }
    endSolve(rhs.cols(), watch);
  }

 private:
  Eigen::MatrixXd dense_;
  Eigen::LLT<Eigen::MatrixXd, Eigen::Upper> factor_;
};

}  // namespace

std::unique_ptr<SparseSolver> makeDenseSolver() { return std::make_unique<DenseSolver>(); }

}  // namespace asyncfem::detail
