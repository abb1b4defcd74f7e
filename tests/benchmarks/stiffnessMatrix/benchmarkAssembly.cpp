// SPDX-License-Identifier: BSD-3-Clause
// Pattern construction and stiffness assembly on box meshes of ~10k, ~100k and ~1M tets,
// against a naive triplet (setFromTriplets) assembly measured in the same run.
#include "benchmarkCommon.hpp"

#include <asyncfem/stiffnessMatrix/assembler.hpp>

#include <benchmark/benchmark.h>
#include <omp.h>

#include <Eigen/SparseCore>

#include <vector>

namespace asyncfem::bench {
namespace {

void setMeshCounters(benchmark::State& state, const TetMesh& mesh) {
  state.counters["tets"] = mesh.numElements();
  state.counters["dofs"] = mesh.numDofs();
  state.counters["threads"] = omp_get_max_threads();
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
  for (auto _ : state) {
    assembleLinearStiffness(mesh, assembler, stiffness);
    benchmark::DoNotOptimize(stiffness.valuePtr());
  }
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
  for (auto _ : state) {
    const MatrixAssembler assembler(mesh);
    Eigen::SparseMatrix<double> stiffness = linearStiffnessMatrix(mesh, assembler);
    benchmark::DoNotOptimize(stiffness.valuePtr());
  }
  setMeshCounters(state, mesh);
  state.counters["peakRSS_MiB"] = peakResidentMegabytes();
}

// Baseline: 144 triplets per element, then Eigen's setFromTriplets (serial), every time.
void tripletBaseline(benchmark::State& state) {
  const TetMesh& mesh = boxMesh(static_cast<int>(state.range(0)));
  resetPeakResident();
  for (auto _ : state) {
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
    benchmark::DoNotOptimize(stiffness.valuePtr());
  }
  setMeshCounters(state, mesh);
  state.counters["peakRSS_MiB"] = peakResidentMegabytes();
}

BENCHMARK(patternConstruction)->Apply(meshSizes)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(assembleStiffness)->Apply(meshSizes)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(assembleStiffnessStdFunction)->Apply(meshSizes)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(patternAndStiffness)->Apply(meshSizes)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(tripletBaseline)->Apply(meshSizes)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace asyncfem::bench
