// SPDX-License-Identifier: BSD-3-Clause
// CHOLMOD factorization and one solve of the free system M + h^2 K of a box clamped at
// x = 0, with one extra solve as the in-run baseline (factor / solve ratio) and the
// factorization's flop rate (factorGFLOPs, against benchmarkMachinePeak's blasDgemm).
#include <benchmark/benchmark.h>
#include <time.h>

#include <Eigen/SparseCore>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>

#include "benchmarkCommon.hpp"

namespace asyncfem::bench {
namespace {

/// CPU seconds of the calling thread (all of a one-thread factorization's work, whatever
/// else the machine runs).
double threadCpuSeconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

void cholmodFreeSystem(benchmark::State& state) {
  const TetMesh& mesh = boxMesh(static_cast<int>(state.range(0)));
  resetPeakResident();
  Eigen::SparseMatrix<double> freeSystem;
  {
    const MatrixAssembler assembler(mesh);
    const Eigen::SparseMatrix<double> stiffness = linearStiffnessMatrix(mesh, assembler);
    const Eigen::SparseMatrix<double> mass = massMatrix(mesh, assembler, MassType::consistent);
    const double timestep = 1e-3;
    Eigen::SparseMatrix<double> system;
    combine({1.0, timestep * timestep}, {&mass, &stiffness}, system);
    const FreeDofs dofs = FreeDofs::fromFixedVertices(mesh.numVertices(), mesh.vertexSet("xmin"));
    freeSystem = SubmatrixExtractor(system, dofs.freeToFull(), dofs.freeToFull()).extract(system);
  }
  const Eigen::VectorXd rhs = Eigen::VectorXd::Ones(freeSystem.rows());
  SolverStats stats;
  double analyzeSeconds = 0.0, factorSeconds = 0.0, solveSeconds = 0.0, factorCpuSeconds = 0.0;
  for (auto _ : state) {
    const std::unique_ptr<SparseSolver> solver = makeSparseSolver(SolverKind::cholmod);
    Stopwatch watch;
    watch.start();
    solver->analyzePattern(freeSystem);
    analyzeSeconds = watch.stop();
    watch.start();
    const double cpuBefore = threadCpuSeconds();
    solver->factorize(freeSystem);
    factorCpuSeconds = threadCpuSeconds() - cpuBefore;
    factorSeconds = watch.stop();
    watch.start();
    const Eigen::VectorXd solution = solver->solve(rhs);
    solveSeconds = watch.stop();
    benchmark::DoNotOptimize(solution.data());
    stats = solver->stats();
  }
  state.counters["tets"] = mesh.numElements();
  state.counters["freeDofs"] = static_cast<double>(freeSystem.rows());
  state.counters["nnzA"] = static_cast<double>(freeSystem.nonZeros());
  state.counters["nnzL"] = static_cast<double>(stats.factorNonZeros);
  state.counters["factorGflop"] = stats.factorFlops * 1e-9;
  state.counters["analyze_s"] = analyzeSeconds;
  state.counters["factor_s"] = factorSeconds;
  // The numeric factorization's rate, to be read against blasDgemm's (benchmarkMachinePeak).
  state.counters["factorGFLOPs"] = factorSeconds > 0.0 ? stats.factorFlops * 1e-9 / factorSeconds : 0.0;
  // Over this thread's CPU time: the one-thread rate on a shared machine (with more BLAS
  // threads their work is not counted, so only OMP_NUM_THREADS=1 reads it).
  state.counters["factorGFLOPsCpu"] = factorCpuSeconds > 0.0 ? stats.factorFlops * 1e-9 / factorCpuSeconds : 0.0;
  state.counters["solve_s"] = solveSeconds;
  state.counters["factorPerSolve"] = solveSeconds > 0.0 ? factorSeconds / solveSeconds : 0.0;
  state.counters["peakRSS_MiB"] = peakResidentMegabytes();
}

// 10k, 100k, 384k and 1M tets; the largest factor takes about 8 GB and minutes on two
// cores, so every size runs once (the factor time dwarfs the timer's resolution).
BENCHMARK(cholmodFreeSystem)
    ->Arg(12)
    ->Arg(26)
    ->Arg(40)
    ->Arg(55)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace asyncfem::bench
