// SPDX-License-Identifier: BSD-3-Clause
// What this machine can reach, measured in the same run as the factorizations, so that
// their GFLOP/s are read against it: the BLAS's dense matrix product and a STREAM-style
// triad (the kernels of ../machineRates.hpp, which benchmarkHyperelastic shares).
#include <benchmark/benchmark.h>
#include <omp.h>

#include "../machineRates.hpp"

namespace {

using asyncfem::bench::DenseProduct;
using asyncfem::bench::TriadArrays;

void blasDgemm(benchmark::State& state) {
  DenseProduct product(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    product.run();
    benchmark::DoNotOptimize(product.result());
    benchmark::ClobberMemory();
  }
  state.counters["GFLOPs"] = benchmark::Counter(product.flops() * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["threads"] = omp_get_max_threads();
}

void streamTriad(benchmark::State& state) {
  TriadArrays triad;
  for (auto _ : state) {
    triad.run();
    benchmark::DoNotOptimize(triad.result());
    benchmark::ClobberMemory();
  }
  state.counters["GBps"] =
      benchmark::Counter(TriadArrays::bytes() * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["threads"] = omp_get_max_threads();
}

// Rates over wall time (what several threads reach on an idle machine) and over the main
// thread's CPU time (one thread: what the code reaches while the machine is shared).
BENCHMARK(blasDgemm)->Arg(1000)->Arg(2000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(blasDgemm)->Name("blasDgemmCpu")->Arg(1000)->Arg(2000)->Unit(benchmark::kMillisecond);
BENCHMARK(streamTriad)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(streamTriad)->Name("streamTriadCpu")->Unit(benchmark::kMillisecond);

}  // namespace
