// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>

#include <suitesparse/cholmod.h>
#include <suitesparse/umfpack.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

namespace asyncfem {

std::string toString(SolverKind kind) {
  switch (kind) {
    case SolverKind::cholmod: return "cholmod";
    case SolverKind::umfpack: return "umfpack";
    case SolverKind::eigenLDLT: return "eigen-ldlt";
    case SolverKind::eigenLU: return "eigen-lu";
  }
  return "unknown";
}

SolverKind parseSolverKind(const std::string& name) {
  for (SolverKind kind : {SolverKind::cholmod, SolverKind::umfpack, SolverKind::eigenLDLT, SolverKind::eigenLU}) {
    if (toString(kind) == name) return kind;
  }
  throw Error("unknown sparse solver '" + name + "' (valid: cholmod, umfpack, eigen-ldlt, eigen-lu)");
}

namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;

/// The pattern a solver was analysed with, to reject factorize() calls on another one.
struct PatternSignature {
  Eigen::Index rows = -1;
  std::vector<int> outer, inner;

  void record(const SparseMatrix& a) {
    rows = a.rows();
    outer.assign(a.outerIndexPtr(), a.outerIndexPtr() + a.outerSize() + 1);
    inner.assign(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros());
  }
  bool matches(const SparseMatrix& a) const {
    return a.rows() == rows && a.cols() == rows && static_cast<std::size_t>(a.nonZeros()) == inner.size() &&
           std::equal(outer.begin(), outer.end(), a.outerIndexPtr()) &&
           std::equal(inner.begin(), inner.end(), a.innerIndexPtr());
  }
};

void requireSquareCompressed(const SparseMatrix& a, const char* who) {
  if (a.rows() != a.cols()) {
    throw Error(std::string(who) + ": matrix is " + std::to_string(a.rows()) + " x " + std::to_string(a.cols()) +
                ", not square");
  }
  if (!a.isCompressed()) throw Error(std::string(who) + ": matrix must be compressed (call makeCompressed())");
}

/// Shared checks and bookkeeping of every backend.
class SolverBase : public SparseSolver {
protected:
  void beginAnalyze(const SparseMatrix& a, const char* who) {
    requireSquareCompressed(a, who);
    signature_.record(a);
    factored_ = false;
  }
  void beginFactorize(const SparseMatrix& a, const char* who) const {
    requireSquareCompressed(a, who);
    if (signature_.rows < 0) throw Error(std::string(who) + ": factorize() called before analyzePattern()");
    if (!signature_.matches(a)) {
      throw Error(std::string(who) +
                  ": the matrix pattern differs from the analysed one; call analyzePattern() again");
    }
  }
  void beginSolve(const Eigen::Ref<const Eigen::MatrixXd>& rhs, const char* who) const {
    if (!factored_) throw Error(std::string(who) + ": solve() called before a successful factorize()");
    if (rhs.rows() != signature_.rows) {
      throw Error(std::string(who) + ": right-hand side has " + std::to_string(rhs.rows()) + " rows, expected " +
                  std::to_string(signature_.rows));
    }
  }
  PatternSignature signature_;
  bool factored_ = false;
};

// ---------------------------------------------------------------------------------------------
// CHOLMOD supernodal Cholesky, METIS ordering.

class CholmodSolver final : public SolverBase {
public:
  CholmodSolver() {
    cholmod_start(&common_);
    common_.print = 0;
    common_.error_handler = nullptr;
    common_.supernodal = CHOLMOD_SUPERNODAL;
    common_.nmethods = 1;
    common_.method[0].ordering = CHOLMOD_METIS;
    common_.postorder = 1;
  }
  ~CholmodSolver() override {
    if (factor_) cholmod_free_factor(&factor_, &common_);
    cholmod_finish(&common_);
  }
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  SolverKind kind() const override { return SolverKind::cholmod; }

  void analyzePattern(const SparseMatrix& a) override {
    Stopwatch watch;
    beginAnalyze(a, "cholmod");
    if (factor_) cholmod_free_factor(&factor_, &common_);
    cholmod_sparse view = viewOf(a);
    factor_ = cholmod_analyze(&view, &common_);
    if (!factor_ || common_.status < CHOLMOD_OK) {
      throw Error("cholmod: symbolic analysis failed (status " + std::to_string(common_.status) + ")");
    }
    stats_.factorNonZeros = static_cast<long long>(common_.lnz);
    stats_.factorFlops = common_.fl;
    stats_.solveFlopsPerRhs = 4.0 * common_.lnz;
    ++stats_.analyses;
    stats_.analyzeSeconds += watch.stop();
  }

  void factorize(const SparseMatrix& a) override {
    Stopwatch watch;
    beginFactorize(a, "cholmod");
    cholmod_sparse view = viewOf(a);
    factored_ = false;
    const int ok = cholmod_factorize(&view, factor_, &common_);
    if (!ok || common_.status < CHOLMOD_OK) {
      throw NumericalError("cholmod: numeric factorization failed (status " + std::to_string(common_.status) + ")");
    }
    if (common_.status == CHOLMOD_NOT_POSDEF || factor_->minor < factor_->n) {
      throw NumericalError("cholmod: matrix is not positive definite (failure at column " +
                           std::to_string(factor_->minor) + " of " + std::to_string(factor_->n) + ")");
    }
    factored_ = true;
    ++stats_.factorizations;
    stats_.factorSeconds += watch.stop();
  }

  void solve(const Eigen::Ref<const Eigen::MatrixXd>& rhs, Eigen::MatrixXd& solution) override {
    Stopwatch watch;
    beginSolve(rhs, "cholmod");
    // CHOLMOD reads B through a non-const pointer but does not modify it; copy to keep
    // Ref's stride assumptions out of it.
    Eigen::MatrixXd b = rhs;
    cholmod_dense bView{};
    bView.nrow = static_cast<std::size_t>(b.rows());
    bView.ncol = static_cast<std::size_t>(b.cols());
    bView.nzmax = bView.nrow * bView.ncol;
    bView.d = bView.nrow;
    bView.x = b.data();
    bView.xtype = CHOLMOD_REAL;
    bView.dtype = CHOLMOD_DOUBLE;
    cholmod_dense* x = cholmod_solve(CHOLMOD_A, factor_, &bView, &common_);
    if (!x) throw NumericalError("cholmod: solve failed (status " + std::to_string(common_.status) + ")");
    solution = Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(x->x), b.rows(), b.cols());
    cholmod_free_dense(&x, &common_);
    stats_.solvedRightHandSides += b.cols();
    stats_.solveSeconds += watch.stop();
  }

  std::string ordering() const override {
    if (!factor_) return "none";
    switch (factor_->ordering) {
      case CHOLMOD_METIS: return "metis";
      case CHOLMOD_NESDIS: return "nesdis";
      case CHOLMOD_AMD: return "amd";
      case CHOLMOD_COLAMD: return "colamd";
      case CHOLMOD_NATURAL: return "natural";
      case CHOLMOD_GIVEN: return "given";
      default: return "other";
    }
  }

private:
  /// A cholmod_sparse that points into the Eigen matrix (no copy); stype 1: only the
  /// upper triangle is read, so full-storage symmetric matrices work as they are.
  static cholmod_sparse viewOf(const SparseMatrix& a) {
    cholmod_sparse view{};
    view.nrow = static_cast<std::size_t>(a.rows());
    view.ncol = static_cast<std::size_t>(a.cols());
    view.nzmax = static_cast<std::size_t>(a.nonZeros());
    view.p = const_cast<int*>(a.outerIndexPtr());
    view.i = const_cast<int*>(a.innerIndexPtr());
    view.x = const_cast<double*>(a.valuePtr());
    view.stype = 1;
    view.itype = CHOLMOD_INT;
    view.xtype = CHOLMOD_REAL;
    view.dtype = CHOLMOD_DOUBLE;
    view.sorted = 1;
    view.packed = 1;
    return view;
  }

  cholmod_common common_{};
  cholmod_factor* factor_ = nullptr;
};

// ---------------------------------------------------------------------------------------------
// UMFPACK LU.

class UmfpackSolver final : public SolverBase {
public:
  UmfpackSolver() { umfpack_di_defaults(control_); }
  ~UmfpackSolver() override { release(); }
  UmfpackSolver(const UmfpackSolver&) = delete;
  UmfpackSolver& operator=(const UmfpackSolver&) = delete;

  SolverKind kind() const override { return SolverKind::umfpack; }

  void analyzePattern(const SparseMatrix& a) override {
    Stopwatch watch;
    beginAnalyze(a, "umfpack");
    release();
    const int n = static_cast<int>(a.rows());
    const int status = umfpack_di_symbolic(n, n, a.outerIndexPtr(), a.innerIndexPtr(), a.valuePtr(), &symbolic_,
                                           control_, info_);
    if (status != UMFPACK_OK) throw Error("umfpack: symbolic analysis failed (status " + std::to_string(status) + ")");
    ++stats_.analyses;
    stats_.analyzeSeconds += watch.stop();
  }

  void factorize(const SparseMatrix& a) override {
    Stopwatch watch;
    beginFactorize(a, "umfpack");
    factored_ = false;
    if (numeric_) umfpack_di_free_numeric(&numeric_);
    const int status =
        umfpack_di_numeric(a.outerIndexPtr(), a.innerIndexPtr(), a.valuePtr(), symbolic_, &numeric_, control_, info_);
    if (status == UMFPACK_WARNING_singular_matrix) {
      throw NumericalError("umfpack: matrix is singular");
    }
    if (status != UMFPACK_OK) throw NumericalError("umfpack: numeric factorization failed (status " + std::to_string(status) + ")");
    stats_.factorNonZeros = static_cast<long long>(info_[UMFPACK_LNZ] + info_[UMFPACK_UNZ]);
    stats_.factorFlops = info_[UMFPACK_FLOPS];
    stats_.solveFlopsPerRhs = 2.0 * (info_[UMFPACK_LNZ] + info_[UMFPACK_UNZ]);
    values_ = a;  // umfpack_di_solve needs the matrix for iterative refinement
    factored_ = true;
    ++stats_.factorizations;
    stats_.factorSeconds += watch.stop();
  }

  void solve(const Eigen::Ref<const Eigen::MatrixXd>& rhs, Eigen::MatrixXd& solution) override {
    Stopwatch watch;
    beginSolve(rhs, "umfpack");
    solution.resize(rhs.rows(), rhs.cols());
    Eigen::VectorXd b, x(rhs.rows());
    for (Eigen::Index c = 0; c < rhs.cols(); ++c) {
      b = rhs.col(c);
      const int status = umfpack_di_solve(UMFPACK_A, values_.outerIndexPtr(), values_.innerIndexPtr(),
                                          values_.valuePtr(), x.data(), b.data(), numeric_, control_, info_);
      if (status != UMFPACK_OK) throw NumericalError("umfpack: solve failed (status " + std::to_string(status) + ")");
      solution.col(c) = x;
    }
    stats_.solvedRightHandSides += rhs.cols();
    stats_.solveSeconds += watch.stop();
  }

private:
  void release() {
    if (numeric_) umfpack_di_free_numeric(&numeric_);
    if (symbolic_) umfpack_di_free_symbolic(&symbolic_);
    numeric_ = symbolic_ = nullptr;
  }
  double control_[UMFPACK_CONTROL];
  double info_[UMFPACK_INFO];
  void* symbolic_ = nullptr;
  void* numeric_ = nullptr;
  SparseMatrix values_;
};

// ---------------------------------------------------------------------------------------------
// Eigen fallbacks (no SuiteSparse needed at run time).

template <class Factorization, SolverKind Kind>
class EigenSolver final : public SolverBase {
public:
  SolverKind kind() const override { return Kind; }

  void analyzePattern(const SparseMatrix& a) override {
    Stopwatch watch;
    beginAnalyze(a, name());
    factorization_.analyzePattern(a);
    ++stats_.analyses;
    stats_.analyzeSeconds += watch.stop();
  }

  void factorize(const SparseMatrix& a) override {
    Stopwatch watch;
    beginFactorize(a, name());
    factored_ = false;
    factorization_.factorize(a);
    if (factorization_.info() != Eigen::Success) {
      throw NumericalError(std::string(name()) +
                           (Kind == SolverKind::eigenLDLT ? ": matrix is not positive definite" : ": matrix is singular"));
    }
    if constexpr (Kind == SolverKind::eigenLDLT) {
      // LDLT succeeds on indefinite matrices; positive definiteness needs D > 0.
      if ((factorization_.vectorD().array() <= 0.0).any()) {
        throw NumericalError("eigen-ldlt: matrix is not positive definite");
      }
      const long long nnzL = factorization_.matrixL().nestedExpression().nonZeros();
      stats_.factorNonZeros = nnzL;
      // Eigen reports no flop count: estimate sum over columns of (column count)^2.
      stats_.factorFlops = estimateFlops(factorization_.matrixL().nestedExpression());
      stats_.solveFlopsPerRhs = 4.0 * static_cast<double>(nnzL);
    } else {
      const long long nnz = factorization_.nnzL() + factorization_.nnzU();
      stats_.factorNonZeros = nnz;
      stats_.factorFlops = 0.0;  // SparseLU exposes no flop count
      stats_.solveFlopsPerRhs = 2.0 * static_cast<double>(nnz);
    }
    factored_ = true;
    ++stats_.factorizations;
    stats_.factorSeconds += watch.stop();
  }

  void solve(const Eigen::Ref<const Eigen::MatrixXd>& rhs, Eigen::MatrixXd& solution) override {
    Stopwatch watch;
    beginSolve(rhs, name());
    solution = factorization_.solve(Eigen::MatrixXd(rhs));
    stats_.solvedRightHandSides += rhs.cols();
    stats_.solveSeconds += watch.stop();
  }

private:
  static const char* name() { return Kind == SolverKind::eigenLDLT ? "eigen-ldlt" : "eigen-lu"; }
  static double estimateFlops(const SparseMatrix& l) {
    double flops = 0.0;
    for (Eigen::Index c = 0; c < l.outerSize(); ++c) {
      const double count = l.outerIndexPtr()[c + 1] - l.outerIndexPtr()[c];
      flops += count * count;
    }
    return flops;
  }
  Factorization factorization_;
};

using EigenLDLTSolver = EigenSolver<Eigen::SimplicialLDLT<SparseMatrix, Eigen::Upper>, SolverKind::eigenLDLT>;
using EigenLUSolver = EigenSolver<Eigen::SparseLU<SparseMatrix>, SolverKind::eigenLU>;

}  // namespace

std::unique_ptr<SparseSolver> makeSparseSolver(SolverKind kind) {
  switch (kind) {
    case SolverKind::cholmod: return std::make_unique<CholmodSolver>();
    case SolverKind::umfpack: return std::make_unique<UmfpackSolver>();
    case SolverKind::eigenLDLT: return std::make_unique<EigenLDLTSolver>();
    case SolverKind::eigenLU: return std::make_unique<EigenLUSolver>();
  }
  throw Error("makeSparseSolver: unknown solver kind");
}

}  // namespace asyncfem
