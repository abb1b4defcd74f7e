// SPDX-License-Identifier: BSD-3-Clause
// forcesAndTangent() of each hyperelastic model on a deformed box of 6 * cells^3 tets,
// against CorotationalLinearFEM (simple tangent, Vega's default) measured on the same mesh
// and displacement in the same process. Counters: us_per_element (time per call / tets)
// and vs_corotational (time per call / corotational time per call). The *ThroughSvd rows
// turn HyperelasticOptions::invariantPath off (every element through its SVD), the
// baseline of the invariant path in the same run.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <Eigen/SparseCore>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/hyperelasticFEM/factory.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <map>
#include <memory>
#include <random>

namespace asyncfem::bench {
namespace {

struct Setup {
  TetMesh mesh;
  Eigen::VectorXd displacement;
};

// A box of 6 cells^3 tets with a Mooney-Rivlin block matching E, nu, displaced by a
// random 5 % strain so that the SVDs and tangents are generic.
const Setup& setup(int cells) {
  static std::map<int, std::unique_ptr<Setup>> cache;
  auto& entry = cache[cells];
  if (!entry) {
    entry = std::make_unique<Setup>();
    BoxMeshSpec spec;
    spec.cells = Eigen::Vector3i::Constant(cells);
    spec.material = Material{"rubber", 1100.0, 1e6, 0.45, MooneyRivlinParameters{5e4, 1.2e5, 1.6e6}};
    entry->mesh = makeBoxMesh(spec);
    std::mt19937 random(1);
    std::uniform_real_distribution<double> offset(-0.05 / cells, 0.05 / cells);
    entry->displacement.resize(entry->mesh.numDofs());
    for (Eigen::Index i = 0; i < entry->displacement.size(); ++i) entry->displacement[i] = offset(random);
  }
  return *entry;
}

// Best of five forcesAndTangent() calls of the corotational model, once per mesh size.
double corotationalSeconds(int cells) {
  static std::map<int, double> measured;
  auto found = measured.find(cells);
  if (found != measured.end()) return found->second;
  const Setup& s = setup(cells);
  CorotationalLinearFEM model(s.mesh);
  Eigen::VectorXd forces;
  Eigen::SparseMatrix<double> stiffness = model.createStiffnessMatrix();
  double best = 1e300;
  for (int run = 0; run < 5; ++run) {
    Stopwatch watch;
    watch.start();
    model.forcesAndTangent(s.displacement, forces, stiffness);
    best = std::min(best, watch.stop());
  }
  measured[cells] = best;
  return best;
}

enum class Variant { corotational, stvkGreen, stvk, neoHookean, mooneyRivlin, neoHookeanThreshold, neoHookeanHandled };

std::unique_ptr<ForceModel> makeModel(Variant variant, const TetMesh& mesh, bool invariantPath) {
  HyperelasticOptions options;
  options.stvkFormulation = StVKFormulation::principalStretches;
  options.invariantPath = invariantPath;
  switch (variant) {
    case Variant::corotational:
      return std::make_unique<CorotationalLinearFEM>(mesh);
    case Variant::stvkGreen:
      return makeHyperelasticForceModel(mesh, HyperelasticMaterialKind::stvk);
    case Variant::stvk:
      return makeHyperelasticForceModel(mesh, HyperelasticMaterialKind::stvk, options);
    case Variant::neoHookean:
      return makeHyperelasticForceModel(mesh, HyperelasticMaterialKind::neoHookean, options);
    case Variant::mooneyRivlin:
      return makeHyperelasticForceModel(mesh, HyperelasticMaterialKind::mooneyRivlin, options);
    case Variant::neoHookeanThreshold:
      options.inversionThreshold = 0.2;
      options.enableCompressionResistance = true;
      return makeHyperelasticForceModel(mesh, HyperelasticMaterialKind::neoHookean, options);
    case Variant::neoHookeanHandled:
      options.inversionThreshold = 0.2;
      options.enforceSPD = true;
      return makeHyperelasticForceModel(mesh, HyperelasticMaterialKind::neoHookean, options);
  }
  return nullptr;
}

void forcesAndTangent(benchmark::State& state, Variant variant, bool invariantPath) {
  const int cells = static_cast<int>(state.range(0));
  const Setup& s = setup(cells);
  const double baseline = corotationalSeconds(cells);
  auto model = makeModel(variant, s.mesh, invariantPath);
  Eigen::VectorXd forces;
  Eigen::SparseMatrix<double> stiffness = model->createStiffnessMatrix();
  model->forcesAndTangent(s.displacement, forces, stiffness);  // sizes the outputs
  double total = 0.0;
  for (auto _ : state) {
    Stopwatch watch;
    watch.start();
    model->forcesAndTangent(s.displacement, forces, stiffness);
    total += watch.stop();
    benchmark::DoNotOptimize(stiffness.valuePtr());
  }
  const double perCall = total / static_cast<double>(state.iterations());
  state.counters["tets"] = s.mesh.numElements();
  state.counters["threads"] = omp_get_max_threads();
  state.counters["us_per_element"] = 1e6 * perCall / s.mesh.numElements();
  state.counters["vs_corotational"] = perCall / baseline;
}

BENCHMARK_CAPTURE(forcesAndTangent, corotational, Variant::corotational, true)->Arg(12)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, stvkGreenStrain, Variant::stvkGreen, true)->Arg(12)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, stvkPrincipalStretches, Variant::stvk, true)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, stvkThroughSvd, Variant::stvk, false)->Arg(12)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, neoHookean, Variant::neoHookean, true)->Arg(12)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, neoHookeanThroughSvd, Variant::neoHookean, false)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, mooneyRivlin, Variant::mooneyRivlin, true)->Arg(12)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, mooneyRivlinThroughSvd, Variant::mooneyRivlin, false)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, neoHookeanThresholdCompression, Variant::neoHookeanThreshold, true)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, neoHookeanThresholdCompressionThroughSvd, Variant::neoHookeanThreshold, false)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, neoHookeanThresholdSPD, Variant::neoHookeanHandled, true)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace asyncfem::bench
