// SPDX-License-Identifier: BSD-3-Clause
// What this machine can reach, measured in the same run as the factorizations, so that
// their GFLOP/s are read against it: the BLAS's dense matrix product (the kernel CHOLMOD's
// supernodal factorization spends its flops in) and a STREAM-style triad (the memory
// bandwidth that bounds the element loops and the triangular solves). Both follow
// OMP_NUM_THREADS (OpenBLAS reads it when OPENBLAS_NUM_THREADS is unset).
#include <benchmark/benchmark.h>
#include <omp.h>

#include <Eigen/Core>
#include <cstddef>
#include <vector>

extern "C" void dgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k,
                       const double* alpha, const double* a, const int* lda, const double* b, const int* ldb,
                       const double* beta, double* c, const int* ldc);

namespace {

// C = A B for n x n matrices: 2 n^3 flops.
void blasDgemm(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Eigen::MatrixXd a = Eigen::MatrixXd::Random(n, n);
  const Eigen::MatrixXd b = Eigen::MatrixXd::Random(n, n);
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(n, n);
  const double one = 1.0, zero = 0.0;
  for (auto _ : state) {
    dgemm_("N", "N", &n, &n, &n, &one, a.data(), &n, b.data(), &n, &zero, c.data(), &n);
    benchmark::DoNotOptimize(c.data());
    benchmark::ClobberMemory();
  }
  const double flops = 2.0 * n * static_cast<double>(n) * n;
  state.counters["GFLOPs"] = benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["threads"] = omp_get_max_threads();
}

// a = b + s c over three arrays of 2^25 doubles (768 MiB, far beyond any cache): 24 bytes
// moved per entry, as STREAM counts them (the write-allocate read of a is not counted).
void streamTriad(benchmark::State& state) {
  const std::ptrdiff_t size = std::ptrdiff_t{1} << 25;
  std::vector<double> a(size), b(size), c(size);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t i = 0; i < size; ++i) {
    a[i] = 0.0;
    b[i] = 1.0;
    c[i] = 2.0;
  }
  const double scale = 3.0;
  for (auto _ : state) {
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t i = 0; i < size; ++i) a[i] = b[i] + scale * c[i];
    benchmark::DoNotOptimize(a.data());
    benchmark::ClobberMemory();
  }
  state.counters["GBps"] =
      benchmark::Counter(24.0 * static_cast<double>(size) * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["threads"] = omp_get_max_threads();
}

// Rates over wall time (what several threads reach on an idle machine) and over the main
// thread's CPU time (one thread: what the code reaches while the machine is shared).
BENCHMARK(blasDgemm)->Arg(1000)->Arg(2000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(blasDgemm)->Name("blasDgemmCpu")->Arg(1000)->Arg(2000)->Unit(benchmark::kMillisecond);
BENCHMARK(streamTriad)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(streamTriad)->Name("streamTriadCpu")->Unit(benchmark::kMillisecond);

}  // namespace
