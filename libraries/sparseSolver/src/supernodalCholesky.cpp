// SPDX-License-Identifier: BSD-3-Clause
#include "detail/supernodalCholesky.hpp"

#include <algorithm>
#include <asyncfem/core/threading.hpp>

// LAPACK and BLAS (Fortran interface, column-major), the kernels CHOLMOD calls too.
extern "C" {
void dpotrf_(const char* uplo, const int* n, double* a, const int* lda, int* info);
void dtrsm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m, const int* n,
            const double* alpha, const double* a, const int* lda, double* b, const int* ldb);
void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k, const double* alpha, const double* a,
            const int* lda, const double* beta, double* c, const int* ldc);
}

namespace asyncfem::detail {

void SupernodalCholesky::prepare(const SupernodalArrays<double>& factor, const int* perm,
                                 const Eigen::SparseMatrix<double>& a) {
  structure_ = factor;
  const int n = factor.size;
  columnSupernode_.assign(static_cast<std::size_t>(n), 0);
  for (int s = 0; s < factor.supernodes; ++s)
    for (int c = factor.super[s]; c < factor.super[s + 1]; ++c) columnSupernode_[static_cast<std::size_t>(c)] = s;
  std::vector<int> inverse(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) inverse[static_cast<std::size_t>(perm[i])] = i;
  // Each upper-triangle entry (i, j) of a is entry (max, min) of P A P^T's lower triangle,
  // in the supernode of its column: the entries are counted per supernode, sorted into one
  // array by a counting sort, then placed through each supernode's row positions.
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const auto supernodeOf = [&](int k, int j) {
    const int p = inverse[static_cast<std::size_t>(inner[k])], q = inverse[static_cast<std::size_t>(j)];
    return columnSupernode_[static_cast<std::size_t>(std::min(p, q))];
  };
  std::vector<int> start(static_cast<std::size_t>(factor.supernodes) + 1, 0);
  for (int j = 0; j < n; ++j)
    for (int k = outer[j]; k < outer[j + 1]; ++k)
      if (inner[k] <= j) ++start[static_cast<std::size_t>(supernodeOf(k, j)) + 1];
  for (int s = 0; s < factor.supernodes; ++s) start[s + 1] += start[s];
  std::vector<int> next(start.begin(), start.end() - 1), sorted(static_cast<std::size_t>(start.back())),
      sortedColumn(sorted.size());
  for (int j = 0; j < n; ++j)
    for (int k = outer[j]; k < outer[j + 1]; ++k)
      if (inner[k] <= j) {
        const auto slot = static_cast<std::size_t>(next[static_cast<std::size_t>(supernodeOf(k, j))]++);
        sorted[slot] = k;
        sortedColumn[slot] = j;
      }
  target_.assign(static_cast<std::size_t>(a.nonZeros()), -1);
  rowPosition_.assign(static_cast<std::size_t>(n), -1);
  int widest = 0;
  for (int s = 0; s < factor.supernodes; ++s) {
    const int rows = factor.pi[s + 1] - factor.pi[s];
    widest = std::max(widest, rows - (factor.super[s + 1] - factor.super[s]));
    for (int r = 0; r < rows; ++r) rowPosition_[static_cast<std::size_t>(factor.rows[factor.pi[s] + r])] = r;
    for (int e = start[static_cast<std::size_t>(s)]; e < start[static_cast<std::size_t>(s) + 1]; ++e) {
      const int k = sorted[static_cast<std::size_t>(e)];
      const int p = inverse[static_cast<std::size_t>(inner[k])];
      const int q = inverse[static_cast<std::size_t>(sortedColumn[static_cast<std::size_t>(e)])];
      target_[static_cast<std::size_t>(k)] = factor.px[s] + (std::min(p, q) - factor.super[s]) * rows +
                                             rowPosition_[static_cast<std::size_t>(std::max(p, q))];
    }
  }
  // dsyrk writes the buffer before reading it (beta = 0): no need to clear it.
  update_.reset(new double[static_cast<std::size_t>(widest) * static_cast<std::size_t>(widest)]);
  prepared_ = true;
}

namespace {
/// Supernodes whose work (rows^2 x columns, about the flops of their dpotrf, dtrsm and dsyrk)
/// is below this run their BLAS calls on one thread. Measured at OMP_NUM_THREADS=2 on the
/// 2-core machine (corotationalBenchmark 30 --toolkit-only exact, factorization ms per step,
/// two runs each): bridge-sized 23.8-25.8 with every call on the BLAS's threads, 18.4-23.5
/// with this threshold; dragon-sized 225 either way, but 281-302 with every call on one
/// thread (its largest supernodes gain from two).
constexpr double kThreadedBlasWork = 1e7;
}  // namespace

bool SupernodalCholesky::factor(const Eigen::SparseMatrix<double>& a, double* values, std::size_t valueCount) {
  // Small supernodes on one BLAS thread: a call that wakes the BLAS's own threads pays a
  // futex wake-up and leaves them spinning (sched_yield) for a while on cores the caller's
  // OpenMP threads want (bridge-sized corotational step at two threads, kThreadedBlasWork).
  // Large ones on factorBlasThreads() (1 unless the user sets more): a count that followed
  // the machine's load would change the factor's last bits with it, and beside other work
  // OpenBLAS's threads wait on each other (a 27k-DOF factorization took 6.6 s instead of
  // 0.37 s beside a two-job build on 2 cores).
  ScopedBlasThreads blas(1);
  const int large = factorBlasThreads();
  std::fill(values, values + valueCount, 0.0);
  const double* entries = a.valuePtr();
  for (std::size_t k = 0; k < target_.size(); ++k) {
    if (target_[k] >= 0) values[target_[k]] += entries[k];
  }
  const SupernodalArrays<double>& f = structure_;
  const double one = 1.0, zero = 0.0;
  for (int s = 0; s < f.supernodes; ++s) {
    const int columns = f.super[s + 1] - f.super[s];
    const int rows = f.pi[s + 1] - f.pi[s];
    const int below = rows - columns;
    double* block = values + f.px[s];
    blas.allow(static_cast<double>(rows) * rows * columns < kThreadedBlasWork ? 1 : large);
    int info = 0;
    dpotrf_("L", &columns, block, &rows, &info);  // L11 L11^T of the diagonal block, in place
    if (info != 0) return false;
    if (below == 0) continue;
    // L21 = A21 L11^-T, then the ancestors lose L21 L21^T (lower triangle into update_).
    dtrsm_("R", "L", "T", "N", &below, &columns, &one, block, &rows, block + columns, &rows);
    dsyrk_("L", "N", &below, &columns, &one, block + columns, &rows, &zero, update_.get(), &below);
    subtractUpdate(s, values);
  }
  return true;
}

void SupernodalCholesky::subtractUpdate(int s, double* values) {
  const SupernodalArrays<double>& f = structure_;
  const int columns = f.super[s + 1] - f.super[s];
  const int below = (f.pi[s + 1] - f.pi[s]) - columns;
  const int* rowsBelow = f.rows + f.pi[s] + columns;
  // The rows below s are ascending, so the columns they name in one ancestor t are
  // consecutive: one row map per ancestor.
  int j = 0;
  while (j < below) {
    const int t = columnSupernode_[static_cast<std::size_t>(rowsBelow[j])];
    const int targetRows = f.pi[t + 1] - f.pi[t];
    for (int r = 0; r < targetRows; ++r) rowPosition_[static_cast<std::size_t>(f.rows[f.pi[t] + r])] = r;
    for (; j < below && rowsBelow[j] < f.super[t + 1]; ++j) {
      double* column = values + f.px[t] + static_cast<std::ptrdiff_t>(rowsBelow[j] - f.super[t]) * targetRows;
      const double* update =
          update_.get() + static_cast<std::ptrdiff_t>(j) * below;  // column j, leading dimension below
      for (int i = j; i < below; ++i) column[rowPosition_[static_cast<std::size_t>(rowsBelow[i])]] -= update[i];
    }
  }
}

}  // namespace asyncfem::detail
