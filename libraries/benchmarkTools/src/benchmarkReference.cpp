// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/benchmarkTools/benchmarkReference.hpp>
#include <asyncfem/benchmarkTools/sceneReference.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <cmath>
#include <sstream>

namespace asyncfem {

namespace {

std::string seconds(double value) {
  std::ostringstream out;
  out.precision(3);
  out << value << " s";
  return out.str();
}

BenchmarkReference modalReference(const Scene& scene, const Simulation& baseline, int frames) {
  Stopwatch watch;
  const DynamicSystem& system = baseline.integrator->system();
  Eigen::SparseMatrix<double> stiffness = system.forceModel->createStiffnessMatrix();
  system.forceModel->tangentStiffness(Eigen::VectorXd::Zero(system.numDofs()), stiffness);
  auto modal = std::make_shared<const ModalReference>(system.mass, stiffness, system.freeDofs, system.rayleighMass,
                                                      system.rayleighStiffness);
  BenchmarkReference reference;
  reference.frames = modal->displacements(sceneLoad(scene, baseline), frameTimes(scene, frames));
  reference.modal = modal;
  reference.description =
      "exact modal solution (" + std::to_string(modal->numFree()) + " modes, " + seconds(watch.stop()) + ")";
  return reference;
}

}  // namespace

int referenceStepsPerFrame(const Scene& scene, const Simulation& baseline,
                           const std::vector<BenchmarkConfiguration>& configurations) {
  // In steps per frame, which are whole numbers: frame interval / h_min is the most small
  // steps per frame any configuration takes.
  int finest = 1;
  for (const BenchmarkConfiguration& c : configurations) {
    const int steps = configuredScene(scene, c, 1).timing.stepsPerFrame;
    finest = std::max(finest, steps * largestRatio(configurationRegions(scene, baseline, c)));
  }
  return 4 * finest;
}

BenchmarkReference computeReference(const Scene& scene, const Simulation& baseline,
                                    const std::vector<BenchmarkConfiguration>& configurations, int frames,
                                    ReferenceKind kind, int maxModalDofs) {
  const std::string reason = modalReferenceUnsupportedReason(scene, baseline, maxModalDofs);
  if (kind == ReferenceKind::modal && !reason.empty()) {
    throw Error("--reference modal: not available for this scene: " + reason);
  }
  if (kind != ReferenceKind::trapezoidal && reason.empty()) return modalReference(scene, baseline, frames);
  BenchmarkConfiguration fine;
  fine.integrator = "trapezoidal";
  fine.stepsPerFrame = referenceStepsPerFrame(scene, baseline, configurations);
  Stopwatch watch;
  const BenchmarkRun run = runConfiguration(scene, fine, frames, 1);
  if (!run.completed) throw Error("the trapezoidal reference run failed: " + run.failure);
  BenchmarkReference reference;
  reference.frames = run.frames;
  reference.description = "trapezoidal run at h = " + formatTimestep(run.timestep) + " (" +
                          (reason.empty() ? std::string("requested") : "no modal reference: " + reason) + ", " +
                          seconds(watch.stop()) + ")";
  return reference;
}

std::vector<VertexGroup> errorGroups(const Scene& scene, const Simulation& baseline,
                                     const std::vector<BenchmarkConfiguration>& configurations) {
  std::vector<VertexGroup> groups;
  const auto firstMultirate = std::find_if(configurations.begin(), configurations.end(),
                                           [](const BenchmarkConfiguration& c) { return isMultirate(c.integrator); });
  if (firstMultirate != configurations.end()) {
    const int numVertices = baseline.mesh->numVertices();
    std::vector<bool> fast(static_cast<std::size_t>(numVertices), false);
    for (const AsyncRegion& region : configurationRegions(scene, baseline, *firstMultirate)) {
      std::string name = region.name;
      if (name.empty()) name = std::string("S").append(std::to_string(groups.size()));
      groups.push_back({name, region.vertices});
      for (const int v : region.vertices) fast[static_cast<std::size_t>(v)] = true;
    }
    VertexGroup large{"L", {}};
    for (int v = 0; v < numVertices; ++v) {
      if (!fast[static_cast<std::size_t>(v)]) large.vertices.push_back(v);
    }
    if (!large.vertices.empty()) groups.push_back(large);
  }
  groups.push_back({"all", {}});
  return groups;
}

int chooseVertex(const Trajectory& reference, const std::vector<VertexGroup>& groups, int numVertices) {
  std::vector<int> candidates = groups.size() > 1 ? groups.front().vertices : std::vector<int>{};
  if (candidates.empty()) {
    for (int v = 0; v < numVertices; ++v) candidates.push_back(v);
  }
  int best = candidates.front();
  double bestNorm = -1.0;
  for (const int v : candidates) {
    double peak = 0.0;
    for (const Eigen::VectorXd& u : reference) peak = std::max(peak, u.segment<3>(3 * v).norm());
    if (peak > bestNorm) {
      bestNorm = peak;
      best = v;
    }
  }
  return best;
}

}  // namespace asyncfem
