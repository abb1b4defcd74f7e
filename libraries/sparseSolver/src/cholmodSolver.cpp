// SPDX-License-Identifier: BSD-3-Clause
// CHOLMOD supernodal Cholesky behind SparseSolver.
#include <omp.h>
#include <suitesparse/cholmod.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/core/threading.hpp>
#include <string>

#include "detail/singlePrecisionFactor.hpp"
#include "detail/solverBase.hpp"
#include "detail/supernodalCholesky.hpp"

namespace asyncfem::detail {
namespace {

/// Name of a CHOLMOD ordering code as SparseSolver::ordering() reports it.
std::string cholmodOrderingName(int ordering) {
  switch (ordering) {
    case CHOLMOD_METIS:
      return "metis";
    case CHOLMOD_NESDIS:
      return "nesdis";
    case CHOLMOD_AMD:
      return "amd";
    case CHOLMOD_COLAMD:
      return "colamd";
    case CHOLMOD_NATURAL:
      return "natural";
    case CHOLMOD_GIVEN:
      return "given";
    default:
      return "cholmod-" + std::to_string(ordering);
  }
}

/// Owns one cholmod_common (CHOLMOD's per-thread state: parameters, workspace,
/// statistics). Each solver has its own, so solvers on different threads share nothing.
class CholmodCommon {
 public:
  CholmodCommon() {
    if (!cholmod_start(&common_)) throw Error("cholmod: cholmod_start failed");
    // Libraries never print: CHOLMOD reports through common_.status, which the callers
    // turn into exceptions after every call.
    common_.print = 0;
    common_.error_handler = nullptr;
  }
  ~CholmodCommon() { cholmod_finish(&common_); }
  CholmodCommon(const CholmodCommon&) = delete;
  CholmodCommon& operator=(const CholmodCommon&) = delete;

  cholmod_common* get() { return &common_; }
  cholmod_common* operator->() { return &common_; }

 private:
  cholmod_common common_{};
};

class CholmodSolver final : public SolverBase, public SupernodalFactorSource {
 public:
  explicit CholmodSolver(FillOrdering ordering) : fillOrdering_(ordering) {
    common_->supernodal = CHOLMOD_SUPERNODAL;
    chooseOrdering(0);
  }
  ~CholmodSolver() override {
    // Free in reverse order of dependence on the common, which CholmodCommon finishes last.
    freeSolveWorkspace();
    if (factor_) cholmod_free_factor(&factor_, common_.get());
  }
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  SolverKind kind() const override { return SolverKind::cholmod; }
  std::string ordering() const override { return factor_ ? cholmodOrderingName(factor_->ordering) : "none"; }

  void analyzePattern(const SparseMatrix& a) override {
    Stopwatch watch;  // runs from construction
    beginAnalyze(a, "cholmod");
    if (factor_) cholmod_free_factor(&factor_, common_.get());
    own_.clear();
    widest_ = -1;
    cholmod_sparse view = upperTriangleView(a);
    chooseOrdering(a.rows());
    factor_ = cholmod_analyze(&view, common_.get());
    if (!factor_ && common_->status == CHOLMOD_NOT_INSTALLED) {
      // A CHOLMOD built without METIS: fall back to its default strategy (AMD, possibly
      // compared with others); ordering() then reports what was used.
      common_->nmethods = 0;
      factor_ = cholmod_analyze(&view, common_.get());
    }
    if (!factor_ || common_->status < CHOLMOD_OK) {
      if (factor_) cholmod_free_factor(&factor_, common_.get());
      signature_ = PatternSignature{};
      throw Error("cholmod: symbolic analysis of the " + std::to_string(a.rows()) + " x " + std::to_string(a.cols()) +
                  " matrix failed (CHOLMOD status " + std::to_string(common_->status) + ")");
    }
    recordFactorCosts();
    allocateOwnFactor();
    ++stats_.analyses;
    stats_.analyzeSeconds += watch.stop();
  }

  void factorize(const SparseMatrix& a) override {
    Stopwatch watch;  // runs from construction
    beginFactorize(a, "cholmod");
    singleState_ = SingleCopy::notMade;
    if (factorOwn(a)) {
      endFactorize(watch);
      return;
    }
    cholmod_sparse view = upperTriangleView(a);
    // CHOLMOD's supernodal factorization opens OpenMP regions of a fixed team size
    // (CHOLMOD_OMP_NUM_THREADS, 4 in Debian's build) whatever OMP_NUM_THREADS says; on a
    // machine with fewer free cores the team waits on itself. With dynamic adjustment on for
    // this call, the runtime gives those regions at most the free cores. Those loops copy and
    // clear values independently, so the factor does not depend on the team size. Measured
    // on the beam scene's corotational async step (2 cores): 17.0 ms to 13.9 ms.
    const int dynamic = omp_get_dynamic();
    omp_set_dynamic(1);
    // CHOLMOD's BLAS calls (dpotrf and dgemm among them, whose values depend on the thread
    // count) on factorBlasThreads(), 1 unless the user sets more: the factor then does not
    // depend on the machine's load, and beside other work OpenBLAS's threads do not wait on
    // each other (a 45k-DOF factorization: 30 s instead of 0.7 s beside two busy processes
    // on 2 cores; idle, two threads gained 1.3x).
    const ScopedBlasThreads blas(factorBlasThreads());
    const int ok = cholmod_factorize(&view, factor_, common_.get());
    omp_set_dynamic(dynamic);
    if (!ok || common_->status < CHOLMOD_OK) {
      throw NumericalError("cholmod: numeric factorization failed (CHOLMOD status " + std::to_string(common_->status) +
                           ")");
    }
    if (common_->status == CHOLMOD_NOT_POSDEF || factor_->minor < factor_->n) {
      // L->minor is the step (in the permuted order) where a pivot was not positive;
      // L->Perm maps it back to the caller's column.
      const std::size_t step = factor_->minor;
      const int column = step < factor_->n ? static_cast<const int*>(factor_->Perm)[step] : -1;
      // The column goes into location().dof, so that callers can name what it stands for.
      NumericalErrorLocation location;
      location.dof = column;
      throw NumericalError("cholmod: matrix is not positive definite: non-positive pivot at column " +
                               std::to_string(column) + " (elimination step " + std::to_string(step) + " of " +
                               std::to_string(factor_->n) + ")",
                           location);
    }
    recordFactorCosts();
    endFactorize(watch);
  }

  void solve(const Eigen::Ref<const Eigen::MatrixXd>& rhs, Eigen::MatrixXd& solution) override {
    Stopwatch watch;  // runs from construction
    beginSolve(rhs, "cholmod");
    solution.resize(rhs.rows(), rhs.cols());
    if (rhs.cols() == 0) return;
    if (rhs.cols() == 1 && solveOneColumn(rhs, solution)) {
      endSolve(1, watch);
      return;
    }
    // CHOLMOD takes B through a non-const pointer but only reads it; a contiguous
    // right-hand side is used in place, a strided one is copied once.
    Eigen::MatrixXd contiguousCopy;
    const double* bData = rhs.data();
    if (rhs.outerStride() != rhs.rows()) {
      contiguousCopy = rhs;
      bData = contiguousCopy.data();
    }
    cholmod_dense b{};
    b.nrow = static_cast<std::size_t>(rhs.rows());
    b.ncol = static_cast<std::size_t>(rhs.cols());
    b.nzmax = b.nrow * b.ncol;
    b.d = b.nrow;
    b.x = const_cast<double*>(bData);
    b.xtype = CHOLMOD_REAL;
    b.dtype = CHOLMOD_DOUBLE;
    // One call for all k columns; solve2 keeps X and its workspace between calls. The
    // BLAS on factorBlasThreads(), as in the factorization: dgemm's and dgemv's bits depend
    // on the thread count.
    const ScopedBlasThreads blas(factorBlasThreads());
    if (!cholmod_solve2(CHOLMOD_A, factor_, &b, nullptr, &x_, nullptr, &y_, &e_, common_.get()) ||
        common_->status < CHOLMOD_OK) {
      throw NumericalError("cholmod: solve failed (CHOLMOD status " + std::to_string(common_->status) + ")");
    }
    solution = Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(x_->x), rhs.rows(), rhs.cols());
    endSolve(rhs.cols(), watch);
  }

  /// One column: through a single-precision copy of the factor (made at the first call
  /// after a factorization; half the bytes per substitution), unless the copy disagrees
  /// with the factor (SinglePrecisionFactor::agreesWith); otherwise solve().
  void solveApproximately(const Eigen::Ref<const Eigen::MatrixXd>& rhs, Eigen::MatrixXd& solution) override {
    if (rhs.cols() != 1 || !singleCopyUsable()) {
      solve(rhs, solution);
      return;
    }
    Stopwatch watch;  // runs from construction
    beginSolve(rhs, "cholmod");
    single_.solve(rhs.col(0), singleSolution_);
    solution = singleSolution_;
    endSolve(1, watch);
  }

  bool copyFactor(SinglePrecisionFactor& out) const override {
    SupernodalFactorView view;
    if (!viewFactor(view)) return false;
    out.assign(view);
    return true;
  }

 private:
  /// Whether single_ holds a usable copy of the current factor (made here if not yet).
  bool singleCopyUsable() {
    if (singleState_ == SingleCopy::notMade) {
      const bool made = copyFactor(single_) && single_.agreesWith([this](const Eigen::VectorXd& b, Eigen::VectorXd& x) {
        Eigen::MatrixXd column;
        solve(b, column);
        x = column.col(0);
      });
      singleState_ = made ? SingleCopy::usable : SingleCopy::unusable;
    }
    return singleState_ == SingleCopy::usable;
  }

  /// The numeric factorization by SupernodalCholesky, into CHOLMOD's factor object (whose
  /// solves then apply it). False where CHOLMOD factors: a buffer beyond
  /// SupernodalCholesky::kMaxUpdateEntries, or a pivot that is not positive (CHOLMOD then
  /// locates it for the error message).
  bool factorOwn(const SparseMatrix& a) {
    if (!ownFactorization_ || !numericSupernodal()) return false;
    const SupernodalFactorView view = supernodalArrays();
    if (!own_.preparedFor(view)) own_.prepare(view, view.perm, a);
    if (!own_.factor(a, static_cast<double*>(factor_->x), factor_->xsize)) return false;
    factor_->minor = factor_->n;
    return true;
  }

  /// After the analysis: whether SupernodalCholesky factors (its buffer fits), and if so
  /// the factor's numeric arrays, allocated as CHOLMOD's own factorization would, so that
  /// every factorization of this pattern, the first included, runs the same arithmetic (a
  /// run resumed from a checkpoint then equals the uninterrupted one bit for bit).
  void allocateOwnFactor() {
    ownFactorization_ = factor_->is_super && factor_->nsuper > 0 && SupernodalCholesky::fits(supernodalArrays());
    if (ownFactorization_ && !cholmod_change_factor(CHOLMOD_REAL, /*to_ll=*/1, /*to_super=*/1, /*to_packed=*/1,
                                                    /*to_monotonic=*/1, factor_, common_.get())) {
      ownFactorization_ = false;  // CHOLMOD factors (and allocates) instead
    }
  }

  /// Whether the factor holds the values of a supernodal L L^T with int indices (from a
  /// numeric factorization, successful or not).
  bool numericSupernodal() const {
    return factor_ != nullptr && factor_->x != nullptr && factor_->is_super && factor_->is_ll &&
           factor_->itype == CHOLMOD_INT && factor_->xtype == CHOLMOD_REAL;
  }

  SupernodalFactorView supernodalArrays() const {
    SupernodalFactorView view;
    view.size = static_cast<int>(factor_->n);
    view.supernodes = static_cast<int>(factor_->nsuper);
    view.super = static_cast<const int*>(factor_->super);
    view.pi = static_cast<const int*>(factor_->pi);
    view.px = static_cast<const int*>(factor_->px);
    view.rows = static_cast<const int*>(factor_->s);
    view.perm = static_cast<const int*>(factor_->Perm);
    view.values = static_cast<const double*>(factor_->x);
    return view;
  }

  /// The numeric factor's arrays, when it is a complete supernodal L L^T with int indices.
  bool viewFactor(SupernodalFactorView& view) const {
    if (!numericSupernodal() || factor_->minor < factor_->n) return false;
    view = supernodalArrays();
    return true;
  }

  /// One right-hand side through the supernodes with Eigen's kernels (supernodalSubstitution.hpp,
  /// shared with the single-precision copy) instead of cholmod_solve2 and its two BLAS
  /// calls per supernode, on factors of at most kOneColumnMaxNonZeros entries: 3-5% faster
  /// on the fast regions' A^S (40k-100k entries), even at 1.3M, and 1.3x slower at 7.6M,
  /// where OpenBLAS's kernels on large supernodes win (one thread, box meshes; docs/benchmarks.md,
  /// "Factorizations without OpenMP regions"). False where cholmod_solve2 solves.
  bool solveOneColumn(const Eigen::Ref<const Eigen::MatrixXd>& rhs, Eigen::MatrixXd& solution) {
    constexpr long long kOneColumnMaxNonZeros = 1000000;
    SupernodalFactorView view;
    if (stats_.factorNonZeros > kOneColumnMaxNonZeros || !viewFactor(view)) return false;
    const int n = view.size;
    work_.resize(n);
    for (int i = 0; i < n; ++i) work_[i] = rhs(view.perm[i], 0);
    if (widest_ < 0) {
      widest_ = widestUpdate(view);
      below_.resize(widest_);
    }
    substituteInPlace(view, work_, below_);
    for (int i = 0; i < n; ++i) solution(view.perm[i], 0) = work_[i];
    return true;
  }

  /// Asks for one ordering, no comparison: METIS, the ordering the design calls for, or
  /// with FillOrdering::automatic AMD for a matrix of up to kAmdMaxRows rows.
  void chooseOrdering(Eigen::Index rows) {
    common_->nmethods = 1;
    const bool amd = fillOrdering_ == FillOrdering::automatic && rows <= kAmdMaxRows;
    common_->method[0].ordering = amd ? CHOLMOD_AMD : CHOLMOD_METIS;
    common_->postorder = 1;
  }

  /// lnz and fl are those of the analysed pattern; a refactorization has the same ones.
  void recordFactorCosts() {
    stats_.factorNonZeros = static_cast<long long>(common_->lnz);
    stats_.factorFlops = common_->fl;
    // Forward and back substitution: one multiply and one add per entry of L, each way.
    stats_.solveFlopsPerRhs = 4.0 * common_->lnz;
  }

  void freeSolveWorkspace() {
    if (x_) cholmod_free_dense(&x_, common_.get());
    if (y_) cholmod_free_dense(&y_, common_.get());
    if (e_) cholmod_free_dense(&e_, common_.get());
  }

  /// A cholmod_sparse that points into the Eigen matrix (no copy). stype = 1: CHOLMOD
  /// reads only the upper triangle, so full-storage symmetric matrices work unchanged.
  static cholmod_sparse upperTriangleView(const SparseMatrix& a) {
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
    view.sorted = 1;  // Eigen keeps inner indices sorted in compressed mode
    view.packed = 1;
    return view;
  }

  // Declared first so it is destroyed last: every CHOLMOD object below belongs to it.
  CholmodCommon common_;
  cholmod_factor* factor_ = nullptr;
  FillOrdering fillOrdering_ = FillOrdering::metis;
  cholmod_dense* x_ = nullptr;     ///< solution buffer reused by cholmod_solve2
  cholmod_dense* y_ = nullptr;     ///< cholmod_solve2 workspace
  cholmod_dense* e_ = nullptr;     ///< cholmod_solve2 workspace
  Eigen::VectorXd work_, below_;   ///< solveOneColumn's permuted vector and update buffer
  int widest_ = -1;                ///< widestUpdate of the analysed factor (-1: not yet known)
  bool ownFactorization_ = false;  ///< factorize() runs SupernodalCholesky (allocateOwnFactor)
  SupernodalCholesky own_;
  enum class SingleCopy { notMade, usable, unusable };
  SingleCopy singleState_ = SingleCopy::notMade;  ///< of the current factor (solveApproximately)
  SinglePrecisionFactor single_;
  Eigen::VectorXd singleSolution_;
};

}  // namespace

std::unique_ptr<SparseSolver> makeCholmodSolver(FillOrdering ordering) {
  return std::make_unique<CholmodSolver>(ordering);
}

}  // namespace asyncfem::detail
