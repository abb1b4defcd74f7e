// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Geometry>
#include <algorithm>
#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/benchmarkTools/stabilityStress.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/sceneIO/asyncScene.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <atomic>
#include <cmath>
#include <mutex>
#include <random>
#include <thread>
#include <utility>

namespace asyncfem {

namespace {

constexpr double kLength = 1.0;  // of the bar, along x

// An empty list requests the grid's whole list.
template <typename T>
std::vector<T> chosen(const std::vector<T>& requested, std::vector<T> grid) {
  return requested.empty() ? grid : requested;
}

// Whether name is in the requested list (an empty list requests everything).
bool requested(const std::vector<std::string>& list, const std::string& name) {
  return list.empty() || std::find(list.begin(), list.end(), name) != list.end();
}

// The lowest quality 6 sqrt(2) |V| / l_max^3 of the elements at positions, or a negative
// number when an element's signed volume changed sign against the mesh's rest positions.
double worstQualityAt(const TetMesh& mesh, const Eigen::Matrix3Xd& positions) {
  double worst = 1e300;
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Eigen::Vector4i t = mesh.element(e);
    const Eigen::Vector3d a = positions.col(t[0]), b = positions.col(t[1]), c = positions.col(t[2]),
                          d = positions.col(t[3]);
    const double volume = (b - a).cross(c - a).dot(d - a) / 6.0;
    double longest = 0.0;
    for (const auto& [p, q] : {std::pair{a, b}, {a, c}, {a, d}, {b, c}, {b, d}, {c, d}}) {
      longest = std::max(longest, (p - q).norm());
    }
    const Eigen::Matrix<double, 3, 4> rest = mesh.elementRestPositions(e);
    const double original = (rest.col(1) - rest.col(0)).cross(rest.col(2) - rest.col(0)).dot(rest.col(3) - rest.col(0));
    if (volume * original <= 0.0) return -1.0;
    worst = std::min(worst, 6.0 * std::sqrt(2.0) * std::abs(volume) / std::pow(longest, 3));
  }
  return worst;
}

}  // namespace

StabilityVerdict stabilityVerdict(const StressOutcome& outcome) {
  if (outcome.failedFrame >= 0) return StabilityVerdict::blowUp;
  if (outcome.energyMeasured && outcome.energyGrowth > 1.0 + energyGrowthTolerance) {
    return StabilityVerdict::energyGrowth;
  }
  return StabilityVerdict::stable;
}

std::string toString(StabilityVerdict verdict) {
  switch (verdict) {
    case StabilityVerdict::stable:
      return "stable";
    case StabilityVerdict::energyGrowth:
      return "energy growth";
    case StabilityVerdict::blowUp:
      return "blow-up";
  }
  return "unknown";
}

BoxMeshSpec stressBarSpec(const Eigen::Vector3i& cells, double stiffnessRatio) {
  BoxMeshSpec spec;
  spec.size = Eigen::Vector3d(kLength, 0.25, 0.25);
  spec.cells = cells;
  spec.material = Material{"soft", 1000.0, 1e5, 0.4};
  // The last quarter is stiffer by stiffnessRatio (and lighter, as the paper's stiff parts).
  spec.regions.push_back({"stiff", Eigen::Vector3d(0.75 * kLength, -1, -1), Eigen::Vector3d(2 * kLength, 2, 2),
                          Material{"stiff", 500.0, 1e5 * stiffnessRatio, 0.4}});
  return spec;
}

PerturbedMesh perturbedBoxMesh(const BoxMeshSpec& spec, unsigned seed, double maxShiftCells) {
  const TetMesh regular = makeBoxMesh(spec);
  const Eigen::Vector3d cell = spec.size.cwiseQuotient(spec.cells.cast<double>());
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-maxShiftCells, maxShiftCells);
  for (int attempt = 0; attempt < 20; ++attempt) {
    Eigen::Matrix3Xd positions = regular.restPositions();
    for (int v = 0; v < regular.numVertices(); ++v) {
      for (int c = 0; c < 3; ++c) {
        const double x = positions(c, v);
        const bool boundary =
            std::abs(x - spec.origin[c]) < 1e-12 || std::abs(x - spec.origin[c] - spec.size[c]) < 1e-12;
        const double shift = uniform(rng) * cell[c];  // drawn for every coordinate: the sequence fixes the mesh
        if (!boundary) positions(c, v) += shift;
      }
    }
    const double worst = worstQualityAt(regular, positions);
    if (worst < 1e-3) continue;  // inverted (negative) or nearly flat: draw again
    PerturbedMesh out{TetMesh(positions, regular.elements(), regular.materials(), regular.elementMaterials()), worst};
    for (const auto& [name, members] : regular.elementSets()) out.mesh.setElementSet(name, members);
    for (const auto& [name, members] : regular.vertexSets()) out.mesh.setVertexSet(name, members);
    return out;
  }
  throw Error("could not perturb the box mesh by up to " + std::to_string(maxShiftCells) +
              " cell widths without inverting or flattening an element in 20 draws; use more cells or a smaller "
              "shift");
}

Scene stressScene(const StressCase& run, const std::filesystem::path& meshFile, const std::vector<int>& stiffVertices) {
  Scene scene;
  scene.sourceName = "stress";
  scene.mesh.source = Scene::MeshSource::file;
  scene.mesh.file = meshFile;
  scene.fixed.sets = {"xmin"};
  scene.rayleighAlpha = run.damping.alpha;
  scene.rayleighBeta = run.damping.beta;
  scene.integrator.name = run.integrator;
  overrideFrameTiming(scene, {.timestep = 1.0 / 120.0, .frameCount = 60, .frameRate = 30.0});
  if (run.integrator != "backward-euler") {
    AsyncSettings settings;
    settings.regions = {{"stiff", stiffVertices, run.ratio}};
    if (run.variant == "symmetric") settings.solver.schur = SchurMode::symmetric;
    scene.integrator.options = asyncSettingsJson(settings);
  }
  return scene;
}

StressOutcome runStressFrames(Simulation& simulation, int frames, double freeFrom, double referenceEnergy) {
  StressOutcome outcome;
  Stopwatch watch;
  Integrator& integrator = *simulation.integrator;
  // The loads that stay constant (gravity, endless pulls), built once.
  const Eigen::VectorXd constantLoad = simulation.problem->loads()->constantPart(simulation.problem->numDofs());
  for (int frame = 0; frame < frames; ++frame) {
    try {
      advanceFrame(simulation, frame);
    } catch (const NumericalError& error) {
      outcome.failedFrame = frame;
      outcome.failure = error.what();
      break;
    }
    if (integrator.time() >= freeFrom) {
      outcome.energyMeasured = true;
      const double energy = integrator.mechanicalEnergy() - constantLoad.dot(integrator.displacement());
      if (referenceEnergy < 0.0) referenceEnergy = energy;
      if (referenceEnergy > 0.0) outcome.energyGrowth = std::max(outcome.energyGrowth, energy / referenceEnergy);
    }
    outcome.maxDisplacement = std::max(outcome.maxDisplacement, integrator.displacement().cwiseAbs().maxCoeff());
  }
  outcome.seconds = watch.stop();
  return outcome;
}

StressGrid stressGrid(const StressGridSelection& selection) {
  StressGrid grid;
  grid.stiffnessRatios =
      chosen(selection.stiffnessRatios, selection.full ? std::vector<double>{1, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6}
                                                       : std::vector<double>{1, 1e2, 1e4, 1e6});
  grid.ratios = chosen(selection.ratios,
                       selection.full ? std::vector<int>{1, 2, 8, 32, 100, 200} : std::vector<int>{1, 8, 50, 200});
  for (const StressDamping& damping :
       std::vector<StressDamping>{{"none", 0.0, 0.0}, {"light", 0.1, 1e-4}, {"heavy", 5.0, 1e-2}}) {
    if (requested(selection.dampings, damping.name)) grid.dampings.push_back(damping);
  }
  const std::vector<std::pair<std::string, std::string>> allIntegrators = {
      {"async", ""}, {"async", "symmetric"}, {"multirate-uncoupled", ""}, {"backward-euler", ""}};
  for (const auto& entry : allIntegrators) {
    const std::string name = entry.second.empty() ? entry.first : entry.first + "-" + entry.second;
    if (requested(selection.integrators, name)) grid.integrators.push_back(entry);
  }
  for (const bool perturbed : {false, true}) {
    if (requested(selection.meshes, perturbed ? "perturbed" : "regular")) grid.meshes.push_back(perturbed);
  }
  return grid;
}

std::vector<StressJob> stressJobs(const StressGrid& grid, const Eigen::Vector3i& cells, unsigned seed,
                                  const std::filesystem::path& folder) {
  std::vector<StressJob> jobs;
  for (const double stiffnessRatio : grid.stiffnessRatios) {
    const BoxMeshSpec spec = stressBarSpec(cells, stiffnessRatio);
    for (const bool perturbed : grid.meshes) {
      double quality = 1.0;
      TetMesh mesh;
      if (perturbed) {
        PerturbedMesh moved = perturbedBoxMesh(spec, seed);
        quality = moved.worstQuality;
        mesh = std::move(moved.mesh);
      } else {
        mesh = makeBoxMesh(spec);
      }
      const std::filesystem::path meshFile =
          folder / ("bar-" + std::to_string(jobs.size()) + (perturbed ? "-perturbed" : "") + ".veg");
      writeVeg(meshFile, mesh);
      RegionSelector stiff;
      stiff.elementSets = {"stiff"};
      const std::vector<int> stiffVertices = regionVertices(mesh, stiff);
      for (const StressDamping& damping : grid.dampings) {
        for (const auto& [integrator, variant] : grid.integrators) {
          for (const int ratio : grid.ratios) {
            if (integrator == "backward-euler" && ratio != grid.ratios.front()) continue;  // m does not apply
            jobs.push_back({StressCase{integrator, variant, stiffnessRatio, ratio, damping, perturbed}, meshFile,
                            quality, stiffVertices});
          }
        }
      }
    }
  }
  return jobs;
}

StressOutcome runStressJob(const StressJob& job, int frames) {
  Scene scene = stressScene(job.stressCase, job.meshFile, job.stiffVertices);
  overrideFrameTiming(scene, {.frameCount = frames});
  Simulation simulation = buildSimulation(scene);
  Integrator& integrator = *simulation.integrator;
  const Eigen::Matrix3Xd& rest = simulation.mesh->restPositions();
  Eigen::VectorXd u = Eigen::VectorXd::Zero(integrator.system().numDofs());
  for (int v = 0; v < rest.cols(); ++v) u[3 * v + 1] = 0.02 * rest(0, v) * rest(0, v) / kLength;
  integrator.setState(u, Eigen::VectorXd::Zero(u.size()));
  return runStressFrames(simulation, frames, 0.0, integrator.mechanicalEnergy());  // free from t = 0: E / E_0
}

void runStressJobsInOrder(std::size_t count, int workers, const std::function<StressOutcome(std::size_t)>& work,
                          const std::function<void(std::size_t, const StressOutcome&)>& report) {
  std::vector<StressOutcome> outcomes(count);
  std::vector<char> done(count, 0);
  std::atomic<std::size_t> next{0};
  std::mutex mutex;
  std::size_t reported = 0;
  auto worker = [&] {
    for (std::size_t index = next++; index < count; index = next++) {
      StressOutcome outcome;
      try {
        outcome = work(index);
      } catch (const std::exception& error) {
        outcome.failedFrame = 0;
        outcome.failure = std::string("setup failed: ") + error.what();
      }
      const std::lock_guard<std::mutex> lock(mutex);
      outcomes[index] = outcome;
      done[index] = 1;
      for (; reported < count && done[reported]; ++reported) report(reported, outcomes[reported]);
    }
  };
  std::vector<std::thread> pool;
  for (int w = 1; w < workers; ++w) pool.emplace_back(worker);
  worker();
  for (std::thread& thread : pool) thread.join();
}

std::vector<SceneStressJob> sceneStressJobs(const std::vector<std::string>& integrators,
                                            const std::vector<int>& ratios) {
  std::vector<SceneStressJob> jobs;
  for (const std::string& integrator : integrators) {
    for (const int ratio : ratios) {
      if (integrator == "backward-euler" && ratio != ratios.front()) continue;  // m does not apply
      jobs.push_back({integrator, ratio});
    }
  }
  return jobs;
}

std::vector<AsyncRegion> sceneStressRegions(const Scene& scene) {
  const nlohmann::json& options = scene.integrator.options;
  const bool multirate = scene.integrator.name == "async" || scene.integrator.name == "multirate-uncoupled";
  if (!multirate || !options.contains("regions") || !options["regions"].is_array()) {
    throw Error(scene.sourceName +
                ": integrator: --scene needs an \"async\" or \"multirate-uncoupled\" scene with explicit "
                "regions (not \"auto\")");
  }
  const std::shared_ptr<const Problem> problem = buildProblem(scene);
  const nlohmann::json regionsOnly = {{"regions", options.at("regions")}};
  return parseAsyncOptions(scene, *problem->sharedMesh(), problem->freeDofs(), regionsOnly).regions;
}

Scene sceneForStressJob(const Scene& base, std::vector<AsyncRegion> regions, const SceneStressJob& job, int frames) {
  Scene scene = base;
  overrideFrameTiming(scene, {.frameCount = frames});
  if (job.integrator == "backward-euler") {
    scene.integrator.name = "backward-euler";
    scene.integrator.options = nlohmann::json::object();
    return scene;
  }
  scene.integrator.name = job.integrator == "multirate-uncoupled" ? "multirate-uncoupled" : "async";
  for (AsyncRegion& region : regions) region.ratio = job.ratio;
  scene.integrator.options["regions"] = asyncRegionsJson(regions);
  if (job.integrator == "async-symmetric") scene.integrator.options["schur"] = "symmetric";
  if (scene.integrator.name == "multirate-uncoupled") {
    for (const char* key : {"coupling", "schur", "method", "recovery", "substepStatePrediction"}) {
      scene.integrator.options.erase(key);
    }
  }
  return scene;
}

}  // namespace asyncfem
