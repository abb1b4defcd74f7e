// SPDX-License-Identifier: BSD-3-Clause
// forcesAndTangent() of each hyperelastic model on a deformed box of 6 * cells^3 tets,
// against CorotationalLinearFEM (simple tangent, Vega's default) measured on the same mesh
// and displacement in the same process. Counters: us_per_element (wall time per call /
// tets), cpu_us_per_element (process CPU time per call, all threads, / tets) and
// vs_corotational (time per call / corotational time per call). The *ThroughSvd rows
// turn HyperelasticOptions::invariantPath off (every element through its SVD), the
// baseline of the invariant path in the same run.
//
// Rows with a flop model (see kernelCost()) also report flops_per_element,
// bytes_per_element, the achieved GFLOPs and GBps (per wall second; *_cpu per CPU second of
// each thread) and their fractions of the BLAS dgemm rate and the STREAM-triad bandwidth
// measured in the same process (machineRates.hpp; machine_* counters). The
// *ScalarKernel rows run the corotational model with ElementKernel::scalar, the baseline
// of the batched (SIMD) pass 1 in the same run.
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

#include "../machineRates.hpp"

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

// Best of five forcesAndTangent() calls of the corotational model (each at a displacement
// differing from the previous one), once per mesh size.
double corotationalSeconds(int cells) {
  static std::map<int, double> measured;
  auto found = measured.find(cells);
  if (found != measured.end()) return found->second;
  const Setup& s = setup(cells);
  CorotationalLinearFEM model(s.mesh);
  Eigen::VectorXd forces;
  Eigen::SparseMatrix<double> stiffness = model.createStiffnessMatrix();
  Eigen::VectorXd displacement = s.displacement;
  double best = 1e300;
  for (int run = 0; run < 5; ++run) {
    displacement[0] = -displacement[0];  // no reuse of the previous call's pass 1
    Stopwatch watch;
    watch.start();
    model.forcesAndTangent(displacement, forces, stiffness);
    best = std::min(best, watch.stop());
  }
  measured[cells] = best;
  return best;
}

enum class Variant {
  corotational,
  corotationalExact,
  corotationalScalar,
  corotationalExactScalar,
  stvkGreen,
  stvk,
  neoHookean,
  mooneyRivlin,
  neoHookeanThreshold,
  neoHookeanHandled
};

std::unique_ptr<ForceModel> makeModel(Variant variant, const TetMesh& mesh, bool invariantPath, bool batched) {
  HyperelasticOptions options;
  options.stvkFormulation = StVKFormulation::principalStretches;
  options.invariantPath = invariantPath;
  options.batchedKernel = batched;
  switch (variant) {
    case Variant::corotational:
      return std::make_unique<CorotationalLinearFEM>(mesh);
    case Variant::corotationalExact:
      return std::make_unique<CorotationalLinearFEM>(mesh, TangentKind::exact);
    case Variant::corotationalScalar:
    case Variant::corotationalExactScalar: {
      auto model = std::make_unique<CorotationalLinearFEM>(
          mesh, variant == Variant::corotationalScalar ? TangentKind::simple : TangentKind::exact);
      model->setElementKernel(ElementKernel::scalar);
      return model;
    }
    case Variant::stvkGreen:
      options.stvkFormulation = StVKFormulation::greenStrain;
      return makeHyperelasticForceModel(mesh, HyperelasticMaterialKind::stvk, options);
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

// Arithmetic and memory traffic per element of forcesAndTangent(), counted by hand from
// the code (no hardware counters on this machine); a division, square root, sine or
// logarithm counts as one flop. Zero where no model is given (the SVD paths and the
// inversion-handling variants).
struct KernelCost {
  double flops = 0.0;           // per element, before the Newton steps
  double flopsPerNewton = 0.0;  // per Newton step of the rotation extraction
  double bytes = 0.0;           // per element
};

// Shared pieces (flops):
//   F = I + sum_a u_a g_a^T (3x4 times 4x3, 9 dot products of 4): 66; the hyperelastic
//   models form x = X + u first: 75.
//   Scatter of a 12x12 element tangent through the MatrixAssembler's slots: 144 adds;
//   symmetrizeElementMatrix: 66 pairs x 2 = 132; force scatter: 12 adds.
// Corotational pass 1 (evaluateElements): F 66; the deterministic rotation start 179
// (F^T F 45, |F^T F - I|^2 26, the Newton-Schulz factor 12 and product 45, Gram-Schmidt
// and cross product 39, the symmetric-F test 12) and the gradient floor (|F|) 19; the
// Newton system (R^T F 45, adjugate 18, determinant 5, the rest 18) 86; the stress and
// energy 103; R sigma 45, f = R sigma g 60, h = R g 60; the energy sum 1: 619. A Newton
// step: |a| 6, w = adj a / det 18, |w| 6, Rodrigues 87, R exp 45, new system 86: 248.
// Pass 2 of the simple tangent: per incidence (4 per element) 27 + 4 x 42: 780 per
// element. Exact tangent: the final system and (tr S I - S)^{-1} 95, per element y = R^T x
// and v = y - X 84, K v 276, W 288, Z + K Y 900, K R^T 720, (Z + K Y) W 864, R (.) 720,
// symmetrize 132, scatter 144: 4224.
// Bytes (every access from memory, none cached between elements): corotational pass 1
// reads indices, displacement, g, (lambda V, mu V) 224 and writes R, E, h, f_e 272; the
// simple tangent's pass 2 reads per incidence h, (lambda V, mu V), slots 136 (544), the
// force pass 112; the CSC values (144 per element) are read and written: 2304. Exact: pass
// 1 + (tr S I - S)^{-1} 568, per element K_e, R, the operator, g, X, indices and u 1600,
// slots 64, CSC 2304, forces 112. Hyperelastic: indices, u, g, volume, material 220; the
// element force written and read 192, the force vector read and written 192; slots 64;
// CSC 2304.
KernelCost kernelCost(Variant variant, bool invariantPath) {
  const double hyperelasticBytes = 220.0 + 192.0 + 192.0 + 64.0 + 2304.0;
  // Invariant path without an I2 term (neo-Hookean): det F for the path test 14; C 45,
  // det 14, invariants 20, material derivatives ~40, F^{-T} 42, P 94, g_1..g_3 74, the
  // 3x3 second derivatives 2, g H g^T 540, the identity and T2/T3 terms 498; V P g and the
  // energy 73; K_e = V G^T dP/dF G 1272; symmetrize 132; scatter 144; force scatter 12.
  const double neoHookeanFlops = 75.0 + 14.0 + 1369.0 + 73.0 + 1272.0 + 132.0 + 144.0 + 12.0;
  const double secondInvariantFlops = 153.0;  // B = F F^T and the 27 W_2 terms
  switch (variant) {
    case Variant::corotational:
    case Variant::corotationalScalar:
      return {619.0 + 780.0 + 12.0, 248.0, 224.0 + 272.0 + 544.0 + 112.0 + 2304.0};
    case Variant::corotationalExact:
    case Variant::corotationalExactScalar:
      return {619.0 + 95.0 + 4224.0 + 12.0, 248.0, 568.0 + 1600.0 + 64.0 + 2304.0 + 112.0};
    case Variant::stvkGreen:
      // F 75; E = (F^T F - I) / 2 63; S 16; V F S g 114; h = F g 60, g^T S g 140, g^T g 80,
      // F F^T 45, the 16 blocks 1024; scatter 144 + 12 (no symmetrization).
      return {75.0 + 63.0 + 16.0 + 114.0 + 60.0 + 140.0 + 80.0 + 45.0 + 1024.0 + 156.0, 0.0, hyperelasticBytes};
    case Variant::stvk:
    case Variant::mooneyRivlin:
      if (!invariantPath) return {};
      return {neoHookeanFlops + secondInvariantFlops, 0.0, hyperelasticBytes};
    case Variant::neoHookean:
      if (!invariantPath) return {};
      return {neoHookeanFlops, 0.0, hyperelasticBytes};
    default:
      return {};
  }
}

// Rates of the kernel against the machine's, as counters.
void reportRates(benchmark::State& state, const KernelCost& cost, double newtonStepsPerElement, double wallPerElement,
                 double cpuPerElement) {
  if (cost.flops == 0.0) return;
  const MachineRates& machine = machineRates();
  const double threads = omp_get_max_threads();
  const double flops = cost.flops + (cost.flopsPerNewton * newtonStepsPerElement);
  const double gflops = 1e-9 * flops / wallPerElement;
  const double gflopsCpu = 1e-9 * flops * threads / cpuPerElement;
  const double gbps = 1e-9 * cost.bytes / wallPerElement;
  const double gbpsCpu = 1e-9 * cost.bytes * threads / cpuPerElement;
  state.counters["newton_steps"] = newtonStepsPerElement;
  state.counters["flops_per_element"] = flops;
  state.counters["bytes_per_element"] = cost.bytes;
  state.counters["GFLOPs"] = gflops;
  state.counters["GFLOPs_cpu"] = gflopsCpu;
  state.counters["GBps"] = gbps;
  state.counters["GBps_cpu"] = gbpsCpu;
  state.counters["machine_dgemm_GFLOPs"] = machine.dgemmGflops;
  state.counters["machine_triad_GBps"] = machine.triadGBps;
  if (machine.dgemmGflopsCpu > 0.0) state.counters["flop_fraction_cpu"] = gflopsCpu / machine.dgemmGflopsCpu;
  state.counters["bandwidth_fraction_cpu"] = gbpsCpu / machine.triadGBpsCpu;
}

// batched: HyperelasticOptions::batchedKernel (the default; false: one element at a time).
void forcesAndTangent(benchmark::State& state, Variant variant, bool invariantPath, bool batched = true) {
  const int cells = static_cast<int>(state.range(0));
  const Setup& s = setup(cells);
  const double baseline = corotationalSeconds(cells);
  auto model = makeModel(variant, s.mesh, invariantPath, batched);
  Eigen::VectorXd forces;
  Eigen::SparseMatrix<double> stiffness = model->createStiffnessMatrix();
  Eigen::VectorXd displacement = s.displacement;
  model->forcesAndTangent(displacement, forces, stiffness);  // sizes the outputs
  const auto* corotational = dynamic_cast<const CorotationalLinearFEM*>(model.get());
  const RotationStats before = corotational != nullptr ? corotational->rotationStats() : RotationStats{};
  double total = 0.0;
  const double cpuStart = processCpuSeconds();
  for (auto _ : state) {
    Stopwatch watch;
    watch.start();
    model->forcesAndTangent(displacement, forces, stiffness);
    total += watch.stop();
    benchmark::DoNotOptimize(stiffness.valuePtr());
    // A new displacement each call: the corotational model would otherwise serve its
    // pass 1 from the cache of the previous call (same displacement bits).
    displacement[0] = -displacement[0];
  }
  const double cpuTotal = processCpuSeconds() - cpuStart;
  const double calls = static_cast<double>(state.iterations());
  const double elements = s.mesh.numElements();
  const double perCall = total / calls;
  state.counters["tets"] = elements;
  state.counters["threads"] = omp_get_max_threads();
  state.counters["us_per_element"] = 1e6 * perCall / elements;
  state.counters["cpu_us_per_element"] = 1e6 * cpuTotal / (calls * elements);
  state.counters["vs_corotational"] = perCall / baseline;
  double newtonSteps = 0.0;
  if (corotational != nullptr) {
    const RotationStats& after = corotational->rotationStats();
    newtonSteps = static_cast<double>(after.newtonSteps - before.newtonSteps) /
                  static_cast<double>(std::max(1LL, after.extractions - before.extractions));
  }
  reportRates(state, kernelCost(variant, invariantPath), newtonSteps, perCall / elements,
              cpuTotal / (calls * elements));
}

// Pass 1 of the corotational model alone (elasticEnergy() at a new displacement: F, R,
// stress, element forces and rotated gradients, no assembly), per ElementKernel.
void corotationalPass1(benchmark::State& state, ElementKernel kernel) {
  const Setup& s = setup(static_cast<int>(state.range(0)));
  CorotationalLinearFEM model(s.mesh);
  model.setElementKernel(kernel);
  Eigen::VectorXd displacement = s.displacement;
  double total = 0.0;
  const double cpuStart = processCpuSeconds();
  for (auto _ : state) {
    displacement[0] = -displacement[0];
    Stopwatch watch;
    watch.start();
    benchmark::DoNotOptimize(model.elasticEnergy(displacement));
    total += watch.stop();
  }
  const double calls = static_cast<double>(state.iterations());
  const double elements = s.mesh.numElements();
  state.counters["threads"] = omp_get_max_threads();
  state.counters["us_per_element"] = 1e6 * total / (calls * elements);
  state.counters["cpu_us_per_element"] = 1e6 * (processCpuSeconds() - cpuStart) / (calls * elements);
}

BENCHMARK_CAPTURE(corotationalPass1, batched, ElementKernel::batched)->Arg(12)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(corotationalPass1, scalar, ElementKernel::scalar)->Arg(12)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, corotational, Variant::corotational, true)->Arg(12)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, corotationalExact, Variant::corotationalExact, true)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, corotationalScalarKernel, Variant::corotationalScalar, true)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, corotationalExactScalarKernel, Variant::corotationalExactScalar, true)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, stvkGreenStrain, Variant::stvkGreen, true)->Arg(12)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, stvkGreenStrainOneAtATime, Variant::stvkGreen, true, false)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, stvkPrincipalStretches, Variant::stvk, true)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, stvkPrincipalStretchesOneAtATime, Variant::stvk, true, false)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, stvkThroughSvd, Variant::stvk, false)->Arg(12)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, neoHookean, Variant::neoHookean, true)->Arg(12)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, neoHookeanOneAtATime, Variant::neoHookean, true, false)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, neoHookeanThroughSvd, Variant::neoHookean, false)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, mooneyRivlin, Variant::mooneyRivlin, true)->Arg(12)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, mooneyRivlinOneAtATime, Variant::mooneyRivlin, true, false)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, mooneyRivlinThroughSvd, Variant::mooneyRivlin, false)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, neoHookeanThresholdCompression, Variant::neoHookeanThreshold, true)
    ->Arg(12)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(forcesAndTangent, neoHookeanThresholdCompressionOneAtATime, Variant::neoHookeanThreshold, true, false)
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
