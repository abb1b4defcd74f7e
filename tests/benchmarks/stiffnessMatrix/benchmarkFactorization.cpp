// SPDX-License-Identifier: BSD-3-Clause
// CHOLMOD factorization and one solve of the free system M + h^2 K of a box clamped at
// x = 0, with one extra solve as the in-run baseline (factor / solve ratio) and the
// factorization's flop rate (factorGFLOPs, against benchmarkMachinePeak's blasDgemm);
// and what a PCG iteration preconditioned by the kept factor costs against a
// factorization, with the factor in single and in double precision (keptFactorIteration:
// the measured price that FactorReusingSolver's cost model estimates).
#include <benchmark/benchmark.h>
#include <time.h>

#include <Eigen/SparseCore>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/sparseSolver/factorReusingSolver.hpp>
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

/// M + stiffnessScale h^2 K on the free DOFs of the box clamped at x = 0, h = 1e-3.
Eigen::SparseMatrix<double> freeSystemMatrix(const TetMesh& mesh, double stiffnessScale = 1.0) {
  const MatrixAssembler assembler(mesh);
  const Eigen::SparseMatrix<double> stiffness = linearStiffnessMatrix(mesh, assembler);
  const Eigen::SparseMatrix<double> mass = massMatrix(mesh, assembler, MassType::consistent);
  const double timestep = 1e-3;
  Eigen::SparseMatrix<double> system;
  combine({1.0, stiffnessScale * timestep * timestep}, {&mass, &stiffness}, system);
  const FreeDofs dofs = FreeDofs::fromFixedVertices(mesh.numVertices(), mesh.vertexSet("xmin"));
  return SubmatrixExtractor(system, dofs.freeToFull(), dofs.freeToFull()).extract(system);
}

void cholmodFreeSystem(benchmark::State& state) {
  const TetMesh& mesh = boxMesh(static_cast<int>(state.range(0)));
  resetPeakResident();
  const Eigen::SparseMatrix<double> freeSystem = freeSystemMatrix(mesh);
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

// A factorization of the free system, then PCG solves of the system with K 30% stiffer
// (a kept factor some steps old: several iterations), preconditioned by the factor kept
// in single precision (state.range(1) = 1) or in double. Counters: the factorization and
// one PCG iteration in seconds, their ratio (the measured price of a factorization in
// PCG iterations) beside the cost model's estimate (modelPrice), and flopsPerEntry =
// factorFlops / solveFlopsPerRhs, which the model reads.
void keptFactorIteration(benchmark::State& state) {
  const TetMesh& mesh = boxMesh(static_cast<int>(state.range(0)));
  const Eigen::SparseMatrix<double> factored = freeSystemMatrix(mesh);
  const Eigen::SparseMatrix<double> drifted = freeSystemMatrix(mesh, 1.3);
  const Eigen::VectorXd rhs = Eigen::VectorXd::Ones(factored.rows());
  FactorReuseOptions options;
  options.relativeTolerance = 1e-10;
  options.amortize = false;
  options.refactorAfterIterations = 1000;
  options.maxIterations = 1000;
  options.singlePrecisionPreconditioner = state.range(1) == 1;
  FactorReusingSolver solver(SolverKind::cholmod, options);
  solver.setMatrix(factored);
  Eigen::VectorXd solution;
  solver.solve(rhs, solution);
  solver.setMatrix(drifted);
  double seconds = 0.0;
  for (auto _ : state) {
    Stopwatch watch;
    watch.start();
    solver.solve(rhs, solution);
    seconds += watch.stop();
    benchmark::DoNotOptimize(solution.data());
  }
  const double iterationSeconds = seconds / static_cast<double>(solver.stats().pcgIterations);
  const SolverStats& direct = solver.directStats();
  state.counters["tets"] = mesh.numElements();
  state.counters["singlePrecision"] = solver.stats().singlePrecisionPreconditioner ? 1 : 0;
  state.counters["pcgIterations"] = solver.stats().lastIterations;
  state.counters["factor_s"] = direct.factorSeconds;
  state.counters["iteration_s"] = iterationSeconds;
  state.counters["measuredPrice"] = direct.factorSeconds / iterationSeconds;
  state.counters["modelPrice"] = solver.stats().factorCostInIterations;
  state.counters["flopsPerEntry"] = direct.factorFlops / direct.solveFlopsPerRhs;
}

BENCHMARK(keptFactorIteration)
    ->ArgsProduct({{8, 12, 18, 26}, {1, 0}})
    ->ArgNames({"cells", "single"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(5);

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
