// SPDX-License-Identifier: BSD-3-Clause
// The machine's reachable rates, measured once per process so that the element kernels'
// GFLOP/s and GB/s are read against numbers taken in the same run (and so under the same
// load): the BLAS dense product (dgemm, n = 1000, 2 n^3 flops) and a STREAM-style triad
// a = b + s c over 2^25 doubles (24 bytes per entry, as STREAM counts). Both follow
// OMP_NUM_THREADS. Rates are given per wall second and per process CPU second (summed over
// threads, then multiplied back by the thread count), the second less sensitive to other
// processes on a shared machine.
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
    const int n = 1000;
    const Eigen::MatrixXd a = Eigen::MatrixXd::Random(n, n);
    const Eigen::MatrixXd b = Eigen::MatrixXd::Random(n, n);
    Eigen::MatrixXd c = Eigen::MatrixXd::Zero(n, n);
    const double one = 1.0;
    const double zero = 0.0;
    const Timing t =
        bestOf(5, [&] { dgemm_("N", "N", &n, &n, &n, &one, a.data(), &n, b.data(), &n, &zero, c.data(), &n); });
    const double flops = 2.0 * n * static_cast<double>(n) * n;
    rates.dgemmGflops = 1e-9 * flops / t.wall;
    rates.dgemmGflopsCpu = 1e-9 * flops * threads / t.cpu;
  }
#endif
  const std::ptrdiff_t size = std::ptrdiff_t{1} << 25;
  std::vector<double> x(static_cast<std::size_t>(size));
  std::vector<double> y(static_cast<std::size_t>(size));
  std::vector<double> z(static_cast<std::size_t>(size));
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t i = 0; i < size; ++i) {
    x[static_cast<std::size_t>(i)] = 0.0;
    y[static_cast<std::size_t>(i)] = 1.0;
    z[static_cast<std::size_t>(i)] = 2.0;
  }
  const Timing t = bestOf(5, [&] {
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t i = 0; i < size; ++i) {
      const auto k = static_cast<std::size_t>(i);
      x[k] = y[k] + (3.0 * z[k]);
    }
  });
  const double bytes = 24.0 * static_cast<double>(size);
  rates.triadGBps = 1e-9 * bytes / t.wall;
  rates.triadGBpsCpu = 1e-9 * bytes * threads / t.cpu;
  return rates;
}

/// measureMachineRates() once per process.
inline const MachineRates& machineRates() {
  static const MachineRates rates = measureMachineRates();
  return rates;
}

}  // namespace asyncfem::bench
