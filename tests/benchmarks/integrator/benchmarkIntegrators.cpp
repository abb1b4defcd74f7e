// SPDX-License-Identifier: BSD-3-Clause
// Per-step cost of backward Euler on box meshes (one face fixed), each against its floor
// measured in the same run:
// - linear, prefactored: one step vs one back-substitution with the same factor
//   (target: ratio <= 1.3);
// - corotational FEM (refactoring path): one step vs corotational force + tangent
//   evaluation + numeric refactorization + one solve (target: ratio <= 1.2; symbolic
//   analysis once per run).
//
// Usage: OMP_WAIT_POLICY=passive build/bin/benchmarkIntegrators [--benchmark_filter=...]
// (without it, OpenMP threads left spinning by the element loops compete with the BLAS
// threads of the factorization and the corotational numbers measure that contention).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/forceModel/linearForceModel.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "../benchmarkMachine.hpp"

namespace {

using asyncfem::bench::cpuModel;
using asyncfem::bench::loadAverage;

using asyncfem::Stopwatch;

struct Scene {
  asyncfem::TetMesh mesh;
  std::shared_ptr<const asyncfem::MatrixAssembler> assembler;
  Eigen::SparseMatrix<double> stiffness, mass;
  asyncfem::FreeDofs freeDofs;
};

/// Box 3 x 1 x 1 of near-cubic cells, six tets each; x = 0 face fixed.
const Scene& scene(int cellsAlongLength) {
  static std::map<int, std::unique_ptr<Scene>> cache;
  auto& slot = cache[cellsAlongLength];
  if (!slot) {
    slot = std::make_unique<Scene>();
    asyncfem::BoxMeshSpec spec;
    spec.size = Eigen::Vector3d(3.0, 1.0, 1.0);
    const int cross = std::max(1, cellsAlongLength / 3);
    spec.cells = Eigen::Vector3i(cellsAlongLength, cross, cross);
    slot->mesh = asyncfem::makeBoxMesh(spec);
    slot->assembler = std::make_shared<const asyncfem::MatrixAssembler>(slot->mesh);
    slot->stiffness = asyncfem::linearStiffnessMatrix(slot->mesh, *slot->assembler);
    slot->mass = asyncfem::massMatrix(slot->mesh, *slot->assembler, asyncfem::MassType::consistent);
    slot->freeDofs = asyncfem::FreeDofs::fromFixedVertices(slot->mesh.numVertices(), slot->mesh.vertexSet("xmin"));
  }
  return *slot;
}

asyncfem::DynamicSystem makeSystem(const Scene& s, std::shared_ptr<asyncfem::ForceModel> model) {
  asyncfem::DynamicSystem system;
  system.forceModel = std::move(model);
  system.mass = s.mass;
  system.freeDofs = s.freeDofs;
  system.rayleighMass = 0.0;
  system.rayleighStiffness = 0.0;
  system.externalForce = [](double, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& f) {
    for (Eigen::Index i = 2; i < f.size(); i += 3) f[i] -= 1.0;  // a small downward load
  };
  return system;
}

constexpr double timestep = 1e-3;

/// M + h^2 K on the free DOFs (alpha = beta = 0), as the integrator builds it.
Eigen::SparseMatrix<double> freeSystemMatrix(const Scene& s) {
  const std::vector<int>& free = s.freeDofs.freeToFull();
  asyncfem::SubmatrixExtractor extractor(s.stiffness, free, free);
  const Eigen::SparseMatrix<double> k = extractor.extract(s.stiffness);
  const Eigen::SparseMatrix<double> m = extractor.extract(s.mass);
  Eigen::SparseMatrix<double> a;
  asyncfem::combine({1.0, timestep * timestep}, {&m, &k}, a);
  return a;
}

template <class Work>
double medianSeconds(int repetitions, Work&& work) {
  std::vector<double> times;
  for (int i = 0; i < repetitions; ++i) {
    Stopwatch watch;
    watch.start();
    work();
    times.push_back(watch.stop());
  }
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

void reportMesh(benchmark::State& state, const Scene& s, const asyncfem::SparseSolver& solver) {
  state.counters["tets"] = s.mesh.numElements();
  state.counters["freeDofs"] = s.freeDofs.numFree();
  state.counters["nnzL"] = static_cast<double>(solver.stats().factorNonZeros);
}

void linearBackwardEuler(benchmark::State& state) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  // Floor: one back-substitution with the same factor (same matrix, same solver kind).
  std::unique_ptr<asyncfem::SparseSolver> solver = makeSparseSolver(asyncfem::SolverKind::cholmod);
  solver->compute(freeSystemMatrix(s));
  const Eigen::VectorXd rhs = Eigen::VectorXd::Constant(s.freeDofs.numFree(), 1.0);
  Eigen::MatrixXd x;
  const double solveSeconds = medianSeconds(15, [&] { solver->solve(rhs, x); });

  asyncfem::BackwardEuler integrator(makeSystem(s, std::make_shared<asyncfem::LinearForceModel>(s.stiffness)),
                                     timestep);
  integrator.step();  // warm-up
  Stopwatch watch;
  watch.start();
  for (auto _ : state) integrator.step();
  const double stepSeconds = watch.stop() / static_cast<double>(state.iterations());
  benchmark::DoNotOptimize(integrator.displacement().data());

  reportMesh(state, s, *solver);
  state.counters["step_ms"] = 1e3 * stepSeconds;
  state.counters["solve_ms"] = 1e3 * solveSeconds;
  state.counters["stepOverSolve"] = stepSeconds / solveSeconds;
  state.counters["factorizations"] = static_cast<double>(integrator.stats().factorizations);
}

void corotationalBackwardEuler(benchmark::State& state) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  auto model = std::make_shared<asyncfem::CorotationalLinearFEM>(s.mesh, s.assembler);

  // Floor: force + tangent evaluation, numeric refactorization of the same matrix
  // (symbolic analysis done beforehand, as the integrator does once per run) and one
  // solve, run back to back like in a step; median of each part over 5 repetitions.
  std::unique_ptr<asyncfem::SparseSolver> solver = makeSparseSolver(asyncfem::SolverKind::cholmod);
  const Eigen::SparseMatrix<double> a = freeSystemMatrix(s);
  solver->analyzePattern(a);
  const Eigen::VectorXd rhs = Eigen::VectorXd::Constant(s.freeDofs.numFree(), 1.0);
  const Eigen::VectorXd u = Eigen::VectorXd::Constant(s.mesh.numDofs(), 1e-3);
  Eigen::VectorXd forces;
  Eigen::SparseMatrix<double> tangent = model->createStiffnessMatrix();
  Eigen::MatrixXd x;
  std::vector<double> forceTimes, factorTimes, solveTimes, floorTimes;
  for (int repetition = 0; repetition < 5; ++repetition) {
    Stopwatch force, factor, solve;
    force.start();
    model->forcesAndTangent(u, forces, tangent);
    force.stop();
    factor.start();
    solver->factorize(a);
    factor.stop();
    solve.start();
    solver->solve(rhs, x);
    solve.stop();
    forceTimes.push_back(force.totalSeconds());
    factorTimes.push_back(factor.totalSeconds());
    solveTimes.push_back(solve.totalSeconds());
    floorTimes.push_back(force.totalSeconds() + factor.totalSeconds() + solve.totalSeconds());
  }
  const auto median = [](std::vector<double> values) {
    std::sort(values.begin(), values.end());
    return values[values.size() / 2];
  };
  const double forceSeconds = median(forceTimes), factorSeconds = median(factorTimes);
  const double solveSeconds = median(solveTimes), floorSeconds = median(floorTimes);

  asyncfem::BackwardEuler integrator(makeSystem(s, model), timestep);
  integrator.step();  // warm-up (includes the one symbolic analysis)
  const asyncfem::IntegratorStats before = integrator.stats();
  Stopwatch watch;
  watch.start();
  for (auto _ : state) integrator.step();
  const double stepSeconds = watch.stop() / static_cast<double>(state.iterations());
  const asyncfem::IntegratorStats& after = integrator.stats();
  const auto steps = static_cast<double>(state.iterations());

  reportMesh(state, s, *solver);
  state.counters["step_ms"] = 1e3 * stepSeconds;
  state.counters["floor_ms"] = 1e3 * floorSeconds;
  state.counters["force_ms"] = 1e3 * forceSeconds;
  state.counters["factor_ms"] = 1e3 * factorSeconds;
  state.counters["solve_ms"] = 1e3 * solveSeconds;
  state.counters["stepOverFloor"] = stepSeconds / floorSeconds;
  // Where the integrator's own step time went (its stats), beside the floor's parts.
  state.counters["stepForce_ms"] = 1e3 * (after.forceSeconds - before.forceSeconds) / steps;
  state.counters["stepAssembly_ms"] = 1e3 * (after.assemblySeconds - before.assemblySeconds) / steps;
  state.counters["stepFactor_ms"] = 1e3 * (after.factorizationSeconds - before.factorizationSeconds) / steps;
  state.counters["stepSolve_ms"] = 1e3 * (after.solveSeconds - before.solveSeconds) / steps;
}

// 25 x 8 x 8 cells = 9 600 tets; 54 x 18 x 18 cells = 104 976 tets.
BENCHMARK(linearBackwardEuler)->Arg(25)->Arg(54)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);
BENCHMARK(corotationalBackwardEuler)->Arg(25)->Arg(54)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

}  // namespace

int main(int argc, char** argv) {
  benchmark::AddCustomContext("cpu_model", cpuModel());
  benchmark::AddCustomContext("hardware_threads", std::to_string(std::thread::hardware_concurrency()));
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
