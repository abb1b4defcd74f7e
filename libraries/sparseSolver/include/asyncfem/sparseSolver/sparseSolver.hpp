// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>

namespace asyncfem {

/// Which factorization backs a SparseSolver.
enum class SolverKind {
  cholmod,    ///< CHOLMOD supernodal Cholesky, METIS ordering (SPD matrices; reads the upper triangle)
  umfpack,    ///< UMFPACK LU (any square non-singular matrix)
  eigenLDLT,  ///< Eigen SimplicialLDLT (SPD fallback, no SuiteSparse needed at run time)
  eigenLU,    ///< Eigen SparseLU (unsymmetric fallback)
  dense,  ///< Eigen's blocked dense Cholesky (LLT) of the upper triangle: SPD systems of a few hundred unknowns at most
  /// A SparseSolver implemented outside this library (e.g. the petscBackend library's
  /// distributed solver); makeSparseSolver() cannot create it and parseSolverKind() does
  /// not accept its name.
  external,
};
/// "cholmod", "umfpack", "eigen-ldlt", "eigen-lu", "dense" (and "external").
std::string toString(SolverKind kind);
/// Inverse of toString for the kinds makeSparseSolver() creates; throws asyncfem::Error
/// listing the valid names.
SolverKind parseSolverKind(const std::string& name);

/// Counters a solver keeps; the machine-independent cost figures come from the
/// factorization libraries themselves (CHOLMOD's Common->fl and lnz, UMFPACK's Info).
struct SolverStats {
  long long factorNonZeros = 0;   ///< non-zeros of L (Cholesky) or L+U (LU)
  double factorFlops = 0.0;       ///< flops of the last numeric factorization (Eigen kinds: estimated from the factor)
  double solveFlopsPerRhs = 0.0;  ///< flops of one forward+back substitution (estimate 4*nnz(L) for Cholesky)
  int analyses = 0;
  int factorizations = 0;
  long long solvedRightHandSides = 0;
  double analyzeSeconds = 0.0, factorSeconds = 0.0, solveSeconds = 0.0;  ///< cumulative wall time
};

/// A sparse direct solver: symbolic analysis once per pattern, numeric factorization
/// whenever values change, then any number of solves. Matrices are Eigen column-major
/// with int indices and full storage (both triangles) even for symmetric ones; the
/// Cholesky kinds read only the upper triangle. Every matrix must be square and
/// compressed (asyncfem::Error otherwise). CHOLMOD/UMFPACK types never appear here (pimpl).
/// Threads: one solver object is not thread-safe, but distinct objects share no mutable
/// state (each owns its CHOLMOD common / UMFPACK objects) and may run on distinct threads.
class SparseSolver {
 public:
  virtual ~SparseSolver() = default;

  /// Symbolic analysis (ordering, elimination tree) of A's pattern. A later factorize()
  /// reuses it as long as the matrix keeps this exact pattern (size and index arrays).
  virtual void analyzePattern(const Eigen::SparseMatrix<double>& matrix) = 0;
  /// Numeric factorization of A, which must have the analysed pattern. Throws
  /// asyncfem::NumericalError when A is not positive definite (Cholesky; the message names
  /// the column) or singular (LU); asyncfem::Error when called before analyzePattern() or
  /// with another pattern (the message says to call analyzePattern() again).
  virtual void factorize(const Eigen::SparseMatrix<double>& matrix) = 0;
  /// analyzePattern + factorize.
  void compute(const Eigen::SparseMatrix<double>& matrix) {
    analyzePattern(matrix);
    factorize(matrix);
  }
  /// Solves A X = B for every column of B (n x k). X is resized to n x k. Throws
  /// asyncfem::Error when B does not have n rows or no factorization succeeded yet.
  virtual void solve(const Eigen::Ref<const Eigen::MatrixXd>& rhs, Eigen::MatrixXd& solution) = 0;
  /// Convenience for one right-hand side.
  Eigen::VectorXd solve(const Eigen::VectorXd& rhs) {
    Eigen::MatrixXd x;
    solve(rhs, x);
    return x.col(0);
  }

  /// Iterative solvers: whether a preconditioning matrix besides A serves them better
  /// (e.g. A without the dense blocks that slow an algebraic multigrid down). Direct
  /// solvers: false, the default.
  virtual bool usesPreconditionerMatrix() const { return false; }
  /// That matrix (A's size, SPD, its pattern fixed from call to call), given before each
  /// factorize() of A; ignored by solvers that do not use one.
  virtual void setPreconditionerMatrix(const Eigen::SparseMatrix<double>& matrix) { (void)matrix; }
  /// A fixed, symmetric positive definite approximation of A^{-1} applied to every column
  /// of rhs, for callers that iterate on the exact operator themselves (preconditioned
  /// conjugate gradients): an iterative solver applies its preconditioner once (one
  /// multigrid cycle) instead of iterating to its tolerance; CHOLMOD solves one column with
  /// a single-precision copy of its factor (relative error about 1e-7, half the bytes per
  /// substitution; nearly symmetric only, so iterate with a flexible conjugate-gradient
  /// update), made at the first such call after each factorization, or with the factor
  /// where the copy would not do (entries beyond float's range). Default, and the other
  /// direct solvers: solve().
  virtual void solveApproximately(const Eigen::Ref<const Eigen::MatrixXd>& rhs, Eigen::MatrixXd& solution) {
    solve(rhs, solution);
  }

  virtual SolverKind kind() const = 0;
  /// Fill-reducing ordering in effect after analyzePattern(): "metis", "amd", "colamd",
  /// "natural", ... as the backend reports it ("default" when the backend does not say,
  /// "none" before analyzePattern()). CHOLMOD reports "metis" unless its build lacks METIS
  /// or FillOrdering::automatic chose "amd".
  virtual std::string ordering() const { return "default"; }
  const SolverStats& stats() const { return stats_; }
  void resetStats() { stats_ = SolverStats{}; }

 protected:
  SolverStats stats_;
};

/// The fill-reducing ordering a CHOLMOD solver analyses with (the other kinds keep their own).
enum class FillOrdering {
  /// METIS nested dissection, the least fill on large 3D meshes (the default).
  metis,
  /// AMD up to kAmdMaxRows rows, METIS above. On small matrices AMD analyses 2-3x faster
  /// for as little fill: the 10k-vertex dragon's 2,808-row fast region, 2.4 ms and 280k
  /// factor entries against METIS's 6.3 ms and 298k. For factors analysed often (fast
  /// regions chosen at run time).
  automatic,
};
/// Largest matrix FillOrdering::automatic orders with AMD.
constexpr int kAmdMaxRows = 12000;

/// Creates a solver of the given kind (asyncfem::Error for SolverKind::external).
std::unique_ptr<SparseSolver> makeSparseSolver(SolverKind kind, FillOrdering ordering = FillOrdering::metis);

}  // namespace asyncfem
