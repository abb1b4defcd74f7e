// SPDX-License-Identifier: BSD-3-Clause
// The machine's reachable rates, measured in the same process as what they are read
// against (and so under the same load): the BLAS dense product (dgemm, 2 n^3 flops: the
// kernel CHOLMOD's supernodal factorization spends its flops in) and a STREAM-style triad
// a = b + s c over 2^25 doubles (768 MiB, far beyond any cache; 24 bytes per entry, as
// STREAM counts them, the write-allocate read of a not counted: the bandwidth that bounds
// element loops and triangular solves). Both follow OMP_NUM_THREADS (OpenBLAS reads it
// when OPENBLAS_NUM_THREADS is unset). benchmarkHyperelastic reads machineRates() beside
// its kernels; benchmarkAssembly times the same two kernels as Google benchmarks.
// Define ASYNCFEM_BENCH_HAVE_BLAS and link a BLAS for the dense product.
#pragma once

#include <omp.h>
#include <time.h>

#include <Eigen/Core>
#include <algorithm>
#include <asyncfem/core/stopwatch.hpp>
#include <cstddef>
#include <vector>

#ifdef ASYNCFEM_BENCH_HAVE_BLAS
extern "C" void dgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k,
                       const double* alpha, const double* a, const int* lda, const double* b, const int* ldb,
                       const double* beta, double* c, const int* ldc);
#endif

namespace asyncfem::bench {

#ifdef ASYNCFEM_BENCH_HAVE_BLAS
/// C = A B for random n x n matrices through the BLAS.
class DenseProduct {
 public:
  explicit DenseProduct(int n)
      : n_(n), a_(Eigen::MatrixXd::Random(n, n)), b_(Eigen::MatrixXd::Random(n, n)), c_(Eigen::MatrixXd::Zero(n, n)) {}
  void run() {
    const double one = 1.0;
    const double zero = 0.0;
    dgemm_("N", "N", &n_, &n_, &n_, &one, a_.data(), &n_, b_.data(), &n_, &zero, c_.data(), &n_);
  }
  double flops() const { return 2.0 * n_ * static_cast<double>(n_) * n_; }
  const double* result() const { return c_.data(); }

 private:
  int n_;
  Eigen::MatrixXd a_, b_, c_;
};
#endif

/// x = y + 3 z over three arrays of 2^25 doubles, in parallel (OpenMP, static schedule).
class TriadArrays {
 public:
  TriadArrays() : x_(kSize), y_(kSize), z_(kSize) {
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t i = 0; i < static_cast<std::ptrdiff_t>(kSize); ++i) {
      const auto k = static_cast<std::size_t>(i);
      x_[k] = 0.0;
      y_[k] = 1.0;
      z_[k] = 2.0;
    }
  }
  void run() {
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t i = 0; i < static_cast<std::ptrdiff_t>(kSize); ++i) {
      const auto k = static_cast<std::size_t>(i);
      x_[k] = y_[k] + (3.0 * z_[k]);
    }
  }
  static double bytes() { return 24.0 * static_cast<double>(kSize); }
  const double* result() const { return x_.data(); }

 private:
  static constexpr std::size_t kSize = std::size_t{1} << 25;
  std::vector<double> x_, y_, z_;
};

/// Process CPU seconds (all threads together).
inline double processCpuSeconds() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + (1e-9 * static_cast<double>(now.tv_nsec));
}

/// Wall and CPU seconds of one call of work (best of repeats, each judged by wall time).
struct Timing {
  double wall = 1e300;
  double cpu = 1e300;
};

template <class Work>
Timing bestOf(int repeats, Work&& work) {
  Timing best;
  for (int run = 0; run < repeats; ++run) {
    Stopwatch watch;
    const double cpuStart = processCpuSeconds();
    watch.start();
    work();
    const double wall = watch.stop();
    if (wall < best.wall) best = Timing{wall, processCpuSeconds() - cpuStart};
  }
  return best;
}

/// Rates per wall second and per process CPU second (summed over threads, then multiplied
/// back by the thread count; less sensitive to other processes on a shared machine).
struct MachineRates {
  double dgemmGflops = 0.0;     // per wall second; 0 without a BLAS
  double dgemmGflopsCpu = 0.0;  // per CPU second of each thread
  double triadGBps = 0.0;
  double triadGBpsCpu = 0.0;
};

inline MachineRates measureMachineRates() {
  MachineRates rates;
  const double threads = omp_get_max_threads();
#ifdef ASYNCFEM_BENCH_HAVE_BLAS
  {
    DenseProduct product(1000);
    const Timing t = bestOf(5, [&] { product.run(); });
    rates.dgemmGflops = 1e-9 * product.flops() / t.wall;
    rates.dgemmGflopsCpu = 1e-9 * product.flops() * threads / t.cpu;
  }
#endif
  TriadArrays triad;
  const Timing t = bestOf(5, [&] { triad.run(); });
  rates.triadGBps = 1e-9 * TriadArrays::bytes() / t.wall;
  rates.triadGBpsCpu = 1e-9 * TriadArrays::bytes() * threads / t.cpu;
  return rates;
}

/// measureMachineRates() once per process.
inline const MachineRates& machineRates() {
  static const MachineRates rates = measureMachineRates();
  return rates;
}

}  // namespace asyncfem::bench
