// SPDX-License-Identifier: BSD-3-Clause
// Pattern construction and stiffness assembly on box meshes of ~10k, ~100k and ~1M tets,
// against a naive triplet (setFromTriplets) assembly measured in the same run: the
// tripletRatio counter is (triplet assembly time) / (time per iteration).
#include <benchmark/benchmark.h>
#include <omp.h>

#include <Eigen/SparseCore>
#include <algorithm>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <map>
#include <vector>

#include "benchmarkCommon.hpp"

namespace asyncfem::bench {
namespace {

void setMeshCounters(benchmark::State& state, const TetMesh& mesh) {
  state.counters["tets"] = mesh.numElements();
  state.counters["dofs"] = mesh.numDofs();
  state.counters["threads"] = omp_get_max_threads();
}

Eigen::SparseMatrix<double> tripletAssembly(const TetMesh& mesh);

// Seconds of one triplet assembly of the mesh of this size, measured once per process
// (the best of two runs) so that every benchmark can report its speed-up against it.
double tripletSeconds(int cells) {
  static std::map<int, double> measured;
  auto found = measured.find(cells);
  if (found != measured.end()) return found->second;
  double best = 0.0;
  for (int run = 0; run < 2; ++run) {
    Stopwatch watch;
    watch.start();
    const Eigen::SparseMatrix<double> stiffness = tripletAssembly(boxMesh(cells));
    benchmark::DoNotOptimize(stiffness.valuePtr());
    const double seconds = watch.stop();
    best = run == 0 ? seconds : std::min(best, seconds);
  }
  measured[cells] = best;
  return best;
}

// Adds the counter tripletRatio = (triplet assembly time) / (this benchmark's time per
// iteration); loopSeconds is the wall time of the whole timing loop.
void setTripletRatio(benchmark::State& state, double loopSeconds) {
  const double perIteration = loopSeconds / static_cast<double>(state.iterations());
  state.counters["tripletRatio"] = tripletSeconds(static_cast<int>(state.range(0))) / perIteration;
}

void patternConstruction(benchmark::State& state) {
  const TetMesh& mesh = boxMesh(static_cast<int>(state.range(0)));
  resetPeakResident();
  Eigen::Index nonZeros = 0;
  int colors = 0;
  for (auto _ : state) {
    const MatrixAssembler assembler(mesh);
    nonZeros = assembler.nonZeros();
    colors = assembler.numColors();
    benchmark::DoNotOptimize(nonZeros);
  }
  setMeshCounters(state, mesh);
  state.counters["nnz"] = static_cast<double>(nonZeros);
  state.counters["colors"] = colors;
  state.counters["peakRSS_MiB"] = peakResidentMegabytes();
}

// Values only, into an existing matrix: what corotational re-assembly pays every step.
void assembleStiffness(benchmark::State& state) {
  const TetMesh& mesh = boxMesh(static_cast<int>(state.range(0)));
  resetPeakResident();
  const MatrixAssembler assembler(mesh);
  Eigen::SparseMatrix<double> stiffness = assembler.createMatrix();
  tripletSeconds(static_cast<int>(state.range(0)));  // measured outside the timing loop
  Stopwatch loop;
  loop.start();
  for (auto _ : state) {
    assembleLinearStiffness(mesh, assembler, stiffness);
    benchmark::DoNotOptimize(stiffness.valuePtr());
  }
  setTripletRatio(state, loop.stop());
  setMeshCounters(state, mesh);
  state.counters["nnz"] = static_cast<double>(stiffness.nonZeros());
  state.counters["peakRSS_MiB"] = peakResidentMegabytes();
}

// The same through the public std::function interface with linearElementStiffness per
// element (material lookup, Lame parameters and gradients per call).
void assembleStiffnessStdFunction(benchmark::State& state) {
  const TetMesh& mesh = boxMesh(static_cast<int>(state.range(0)));
  resetPeakResident();
  const MatrixAssembler assembler(mesh);
  Eigen::SparseMatrix<double> stiffness = assembler.createMatrix();
  const MatrixAssembler::ElementMatrixFunction elementStiffness = [&](int e, ElementMatrix& out) {
    const Material& m = mesh.elementMaterial(e);
    out = linearElementStiffness(mesh.elementRestPositions(e), m.youngsModulus, m.poissonRatio);
  };
  for (auto _ : state) {
    assembler.assemble(elementStiffness, stiffness);
    benchmark::DoNotOptimize(stiffness.valuePtr());
  }
  setMeshCounters(state, mesh);
  state.counters["peakRSS_MiB"] = peakResidentMegabytes();
}

// Pattern plus values in one go, as a first assembly costs.
void patternAndStiffness(benchmark::State& state) {
  const TetMesh& mesh = boxMesh(static_cast<int>(state.range(0)));
  resetPeakResident();
  tripletSeconds(static_cast<int>(state.range(0)));
  Stopwatch loop;
  loop.start();
  for (auto _ : state) {
    const MatrixAssembler assembler(mesh);
    Eigen::SparseMatrix<double> stiffness = linearStiffnessMatrix(mesh, assembler);
    benchmark::DoNotOptimize(stiffness.valuePtr());
  }
  setTripletRatio(state, loop.stop());
  setMeshCounters(state, mesh);
  state.counters["peakRSS_MiB"] = peakResidentMegabytes();
}

// Baseline: 144 triplets per element, then Eigen's setFromTriplets (serial).
Eigen::SparseMatrix<double> tripletAssembly(const TetMesh& mesh) {
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(mesh.numElements()) * 144);
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Material& m = mesh.elementMaterial(e);
    const ElementMatrix k = linearElementStiffness(mesh.elementRestPositions(e), m.youngsModulus, m.poissonRatio);
    const Eigen::Vector4i v = mesh.element(e);
    for (int j = 0; j < 12; ++j)
      for (int i = 0; i < 12; ++i) triplets.emplace_back((3 * v[i / 3]) + (i % 3), (3 * v[j / 3]) + (j % 3), k(i, j));
  }
  Eigen::SparseMatrix<double> stiffness(mesh.numDofs(), mesh.numDofs());
  stiffness.setFromTriplets(triplets.begin(), triplets.end());
  return stiffness;
}

void tripletBaseline(benchmark::State& state) {
  const TetMesh& mesh = boxMesh(static_cast<int>(state.range(0)));
  resetPeakResident();
  for (auto _ : state) {
    Eigen::SparseMatrix<double> stiffness = tripletAssembly(mesh);
    benchmark::DoNotOptimize(stiffness.valuePtr());
  }
  setMeshCounters(state, mesh);
  state.counters["peakRSS_MiB"] = peakResidentMegabytes();
}

// The machine may be shared: with --benchmark_repetitions, the minimum over repetitions
// is reported beside mean and median as the least disturbed run.
double minimum(const std::vector<double>& values) { return *std::min_element(values.begin(), values.end()); }

BENCHMARK(patternConstruction)
    ->Apply(meshSizes)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", minimum);
BENCHMARK(assembleStiffness)
    ->Apply(meshSizes)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", minimum);
BENCHMARK(assembleStiffnessStdFunction)
    ->Apply(meshSizes)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", minimum);
BENCHMARK(patternAndStiffness)
    ->Apply(meshSizes)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", minimum);
BENCHMARK(tripletBaseline)
    ->Apply(meshSizes)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", minimum);

}  // namespace
}  // namespace asyncfem::bench
