// SPDX-License-Identifier: BSD-3-Clause
// UMFPACK LU behind SparseSolver.
#include <suitesparse/umfpack.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <string>
#include <vector>

#include "detail/solverBase.hpp"

namespace asyncfem::detail {
namespace {

/// Owns one UMFPACK Symbolic or Numeric object (freed with the matching function).
template <void (*Free)(void**)>
class UmfpackHandle {
 public:
  UmfpackHandle() = default;
  ~UmfpackHandle() { reset(); }
  UmfpackHandle(const UmfpackHandle&) = delete;
  UmfpackHandle& operator=(const UmfpackHandle&) = delete;

  void reset() {
    if (object_) Free(&object_);
    object_ = nullptr;
  }
  void* get() const { return object_; }
  /// Releases the current object and hands out the slot UMFPACK writes a new one into.
  void** resetAndAddress() {
    reset();
    return &object_;
  }

 private:
  void* object_ = nullptr;
};

using SymbolicHandle = UmfpackHandle<umfpack_di_free_symbolic>;
using NumericHandle = UmfpackHandle<umfpack_di_free_numeric>;

class UmfpackSolver final : public SolverBase {
 public:
  UmfpackSolver() {
    umfpack_di_defaults(control_);
    control_[UMFPACK_PRL] = 0;  // never print
  }

  SolverKind kind() const override { return SolverKind::umfpack; }
  std::string ordering() const override { return ordering_; }

  void analyzePattern(const SparseMatrix& a) override {
    Stopwatch watch;  // runs from construction
    beginAnalyze(a, "umfpack");
    numeric_.reset();
    const int n = static_cast<int>(a.rows());
    const int status = umfpack_di_symbolic(n, n, a.outerIndexPtr(), a.innerIndexPtr(), a.valuePtr(),
                                           symbolic_.resetAndAddress(), control_, info_);
    if (status != UMFPACK_OK) {
      symbolic_.reset();
      signature_ = PatternSignature{};
      throw Error("umfpack: symbolic analysis of the " + std::to_string(n) + " x " + std::to_string(n) +
                  " matrix failed (UMFPACK status " + std::to_string(status) + ")");
    }
    ordering_ = orderingName();
    ++stats_.analyses;
    stats_.analyzeSeconds += watch.stop();
  }

  void factorize(const SparseMatrix& a) override {
    Stopwatch watch;  // runs from construction
    beginFactorize(a, "umfpack");
    const int status = umfpack_di_numeric(a.outerIndexPtr(), a.innerIndexPtr(), a.valuePtr(), symbolic_.get(),
                                          numeric_.resetAndAddress(), control_, info_);
    if (status == UMFPACK_WARNING_singular_matrix) {
      numeric_.reset();
      throw NumericalError("umfpack: matrix is singular (" + std::to_string(a.rows()) + " x " +
                           std::to_string(a.cols()) + ", a zero pivot was found)");
    }
    // Other positive statuses are warnings about the determinant, not failures.
    if (status < UMFPACK_OK) {
      numeric_.reset();
      throw NumericalError("umfpack: numeric factorization failed (UMFPACK status " + std::to_string(status) +
                           (status == UMFPACK_ERROR_out_of_memory ? ": out of memory" : "") + ")");
    }
    // Kept for the iterative refinement umfpack_di_solve does with A; the pattern is the
    // analysed one, held in signature_.
    values_.assign(a.valuePtr(), a.valuePtr() + a.nonZeros());
    const double factorEntries = info_[UMFPACK_LNZ] + info_[UMFPACK_UNZ];
    stats_.factorNonZeros = static_cast<long long>(factorEntries);
    stats_.factorFlops = info_[UMFPACK_FLOPS];
    // Forward and back substitution: one multiply and one add per entry of L and U.
    stats_.solveFlopsPerRhs = 2.0 * factorEntries;
    endFactorize(watch);
  }

  void solve(const Eigen::Ref<const Eigen::MatrixXd>& rhs, Eigen::MatrixXd& solution) override {
    Stopwatch watch;  // runs from construction
    beginSolve(rhs, "umfpack");
    solution.resize(rhs.rows(), rhs.cols());
    // UMFPACK solves one column at a time; columns of a Ref are contiguous (inner stride 1).
    for (Eigen::Index c = 0; c < rhs.cols(); ++c) {
      const int status = umfpack_di_solve(UMFPACK_A, signature_.outer.data(), signature_.inner.data(), values_.data(),
                                          solution.col(c).data(), rhs.col(c).data(), numeric_.get(), control_, info_);
      if (status < UMFPACK_OK) {
        throw NumericalError("umfpack: solve of right-hand side " + std::to_string(c) + " failed (UMFPACK status " +
                             std::to_string(status) + ")");
      }
    }
    endSolve(rhs.cols(), watch);
  }

 private:
  /// UMFPACK reports AMD for both of its strategies; the unsymmetric one orders A'A with COLAMD.
  std::string orderingName() const {
    const int used = static_cast<int>(info_[UMFPACK_ORDERING_USED]);
    const bool symmetric = static_cast<int>(info_[UMFPACK_STRATEGY_USED]) == UMFPACK_STRATEGY_SYMMETRIC;
    switch (used) {
      case UMFPACK_ORDERING_AMD:
        return symmetric ? "amd" : "colamd";
      case UMFPACK_ORDERING_METIS:
        return "metis";
      case UMFPACK_ORDERING_GIVEN:
        return "given";
      case UMFPACK_ORDERING_NONE:
        return "natural";
      default:
        return "umfpack-" + std::to_string(used);
    }
  }

  double control_[UMFPACK_CONTROL];
  double info_[UMFPACK_INFO] = {};
  // Numeric depends on Symbolic only during umfpack_di_numeric; order does not matter.
  SymbolicHandle symbolic_;
  NumericHandle numeric_;
  std::vector<double> values_;
  std::string ordering_ = "none";
};

}  // namespace

std::unique_ptr<SparseSolver> makeUmfpackSolver() { return std::make_unique<UmfpackSolver>(); }

}  // namespace asyncfem::detail
