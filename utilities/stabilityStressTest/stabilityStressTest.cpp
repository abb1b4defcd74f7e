// SPDX-License-Identifier: BSD-3-Clause
// stabilityStressTest: free vibration of a two-material bar under every integrator, over a
// grid of stiffness ratios, timestep ratios, damping and mesh quality.
//
//   stabilityStressTest [--frames N] [--full] [--jobs J] [--cells NX NY NZ] [--seed S] [--csv FILE]
//                       [--stiffness-ratios R...] [--ratios M...] [--damping D...] [--integrators I...]
//                       [--meshes regular|perturbed]
//
// Every run starts from a bent bar at rest (u_y = 0.02 x^2 / L, zero velocity) with no
// external force and reports the energy growth (max over frames of mechanical energy /
// initial energy), the first frame with a non-finite value or blow-up (advanceFrame's
// checks: nothing unstable is ever stored) and the maximum displacement. Runs that blow
// up or gain energy are listed by integrator and configuration at the end. With --scene
// SCENE.json it runs a user's multirate scene at each --ratios value instead, printing
// beside the measured energy growth the estimated spectral radius of the scene's linearized
// step (estimateSceneStepGrowth).
// docs/benchmarks.md lists the grid and the results.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <algorithm>
#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/sceneIO/asyncScene.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/sceneIO/stepGrowthCheck.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <limits>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "commandLine.hpp"

namespace {

namespace fs = std::filesystem;
using namespace asyncfem;

struct Options {
  int frames = 100;
  bool full = false;
  std::vector<int> cells{8, 2, 2};
  unsigned seed = 1;
  std::string csv = "stability.csv";
  std::string scene;         // --scene: stress a user's scene instead of the built-in grid
  bool framesGiven = false;  // --frames was on the command line
  int jobs = 1;
  // Narrow the grid (empty: all of it).
  std::vector<double> stiffnessRatios;
  std::vector<int> ratios;
  std::vector<std::string> dampings;     // none, light, heavy
  std::vector<std::string> integrators;  // async, async-symmetric, multirate-uncoupled, backward-euler
  std::vector<std::string> meshes;       // regular, perturbed
};

struct Damping {
  std::string name;
  double alpha, beta;
};

struct Case {
  std::string integrator;  // registry name
  std::string variant;     // "" or "symmetric"
  double stiffnessRatio;
  int ratio;
  Damping damping;
  bool perturbed;
};

struct Outcome {
  double energyGrowth = 0.0;
  bool energyMeasured = false;  ///< false when the loads never end or contact acts
  int failedFrame = -1;
  std::string failure;
  double maxDisplacement = 0.0;
  double seconds = 0.0;
  /// --scene: estimateSceneStepGrowth() of the run's scene, before the run.
  std::optional<StepGrowthEstimate> stepGrowth;
};

constexpr double kLength = 1.0;

BoxMeshSpec barSpec(const Options& options, double stiffnessRatio) {
  BoxMeshSpec spec;
  spec.size = Eigen::Vector3d(kLength, 0.25, 0.25);
  spec.cells = Eigen::Vector3i(options.cells[0], options.cells[1], options.cells[2]);
  spec.material = Material{"soft", 1000.0, 1e5, 0.4};
  // The last quarter is stiffer by stiffnessRatio (and lighter, as the paper's stiff parts).
  spec.regions.push_back({"stiff", Eigen::Vector3d(0.75 * kLength, -1, -1), Eigen::Vector3d(2 * kLength, 2, 2),
                          Material{"stiff", 500.0, 1e5 * stiffnessRatio, 0.4}});
  return spec;
}

// The bar with interior vertices moved randomly by up to 0.4 cell widths per axis: slivers
// and badly shaped elements, never degenerate ones (retries with a new draw otherwise).
TetMesh perturbedBar(const BoxMeshSpec& spec, unsigned seed, double* worstQuality) {
  const TetMesh regular = makeBoxMesh(spec);
  const Eigen::Vector3d cell = spec.size.cwiseQuotient(spec.cells.cast<double>());
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-0.4, 0.4);
  for (int attempt = 0; attempt < 20; ++attempt) {
    Eigen::Matrix3Xd positions = regular.restPositions();
    for (int v = 0; v < regular.numVertices(); ++v) {
      for (int c = 0; c < 3; ++c) {
        const double x = positions(c, v);
        const bool boundary =
            std::abs(x - spec.origin[c]) < 1e-12 || std::abs(x - spec.origin[c] - spec.size[c]) < 1e-12;
        const double shift = uniform(rng) * cell[c];
        if (!boundary) positions(c, v) += shift;
      }
    }
    // Quality: 6 sqrt(2) V / l_max^3 (1 for a regular tet, 0 for a flat one).
    double worst = 1e300;
    bool inverted = false;
    for (int e = 0; e < regular.numElements(); ++e) {
      const Eigen::Vector4i t = regular.element(e);
      const Eigen::Vector3d a = positions.col(t[0]), b = positions.col(t[1]), c = positions.col(t[2]),
                            d = positions.col(t[3]);
      const double volume = (b - a).cross(c - a).dot(d - a) / 6.0;
      double longest = 0.0;
      for (const auto& [p, q] : {std::pair{a, b}, {a, c}, {a, d}, {b, c}, {b, d}, {c, d}}) {
        longest = std::max(longest, (p - q).norm());
      }
      const double original = [&] {
        const Eigen::Matrix<double, 3, 4> rest = regular.elementRestPositions(e);
        return (rest.col(1) - rest.col(0)).cross(rest.col(2) - rest.col(0)).dot(rest.col(3) - rest.col(0));
      }();
      if (volume * original <= 0.0) inverted = true;
      worst = std::min(worst, 6.0 * std::sqrt(2.0) * std::abs(volume) / std::pow(longest, 3));
    }
    if (inverted || worst < 1e-3) continue;
    TetMesh mesh(positions, regular.elements(), regular.materials(), regular.elementMaterials());
    for (const auto& [name, members] : regular.elementSets()) mesh.setElementSet(name, members);
    for (const auto& [name, members] : regular.vertexSets()) mesh.setVertexSet(name, members);
    *worstQuality = worst;
    return mesh;
  }
  throw Error("could not perturb the bar without inverting or flattening an element; use more cells");
}

// The bar scene of a case; multirate integrators get one fast region, the stiff quarter
// (stiffVertices: the vertices of its elements).
Scene sceneFor(const Case& run, const fs::path& meshFile, const std::vector<int>& stiffVertices) {
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

// Runs `frames` frames of a built simulation. Energy growth is max E / E_ref over the
// frames that end at or after `freeFrom` (E = kinetic + elastic - constant loads . u): no
// load changes from then on, so the energy may only stay or decrease. E_ref: `referenceEnergy` when given (> 0), else
// the energy of the first of those frames.
Outcome runSimulation(Simulation& simulation, int frames, double freeFrom, double referenceEnergy = -1.0) {
  Outcome outcome;
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

Outcome runCase(const Case& run, const fs::path& meshFile, const std::vector<int>& stiffVertices, int frames) {
  Scene scene = sceneFor(run, meshFile, stiffVertices);
  overrideFrameTiming(scene, {.frameCount = frames});
  Simulation simulation = buildSimulation(scene);
  Integrator& integrator = *simulation.integrator;
  const Eigen::Matrix3Xd& rest = simulation.mesh->restPositions();
  Eigen::VectorXd u = Eigen::VectorXd::Zero(integrator.system().numDofs());
  for (int v = 0; v < rest.cols(); ++v) u[3 * v + 1] = 0.02 * rest(0, v) * rest(0, v) / kLength;
  integrator.setState(u, Eigen::VectorXd::Zero(u.size()));
  return runSimulation(simulation, frames, 0.0, integrator.mechanicalEnergy());  // free from t = 0: E / E_0
}

std::string describe(const Case& c) {
  std::ostringstream out;
  out << c.integrator << (c.variant.empty() ? "" : " " + c.variant) << ", stiffness ratio " << c.stiffnessRatio;
  if (c.integrator != "backward-euler") out << ", m = " << c.ratio;
  out << ", damping " << c.damping.name << ", " << (c.perturbed ? "perturbed" : "regular") << " mesh";
  return out.str();
}

// Runs work(i) for i in [0, count) on `workers` threads (cases are independent); calls
// report(i, outcome) in index order, under a lock, as soon as cases 0..i are done. A case
// that throws is reported as failed at frame 0.
void runOrdered(std::size_t count, int workers, const std::function<Outcome(std::size_t)>& work,
                const std::function<void(std::size_t, const Outcome&)>& report) {
  std::vector<Outcome> outcomes(count);
  std::vector<char> done(count, 0);
  std::atomic<std::size_t> next{0};
  std::mutex mutex;
  std::size_t reported = 0;
  auto worker = [&] {
    for (std::size_t index = next++; index < count; index = next++) {
      Outcome outcome;
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

// The selection lists the user can narrow: an empty list means the grid's default.
template <typename T>
std::vector<T> chosen(const std::vector<T>& requested, std::vector<T> grid) {
  return requested.empty() ? grid : requested;
}

// The grid a run covers: the full or default lists, narrowed by the options.
struct Grid {
  std::vector<double> stiffnessRatios;
  std::vector<int> ratios;
  std::vector<Damping> dampings;
  std::vector<std::pair<std::string, std::string>> integrators;  // registry name, variant
  std::vector<bool> meshes;                                      // perturbed?
};

// Whether name is in the requested list (an empty list requests everything).
bool requested(const std::vector<std::string>& list, const std::string& name) {
  return list.empty() || std::find(list.begin(), list.end(), name) != list.end();
}

Grid gridOf(const Options& options) {
  Grid grid;
  grid.stiffnessRatios =
      chosen(options.stiffnessRatios, options.full ? std::vector<double>{1, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6}
                                                   : std::vector<double>{1, 1e2, 1e4, 1e6});
  grid.ratios =
      chosen(options.ratios, options.full ? std::vector<int>{1, 2, 8, 32, 100, 200} : std::vector<int>{1, 8, 50, 200});
  for (const Damping& damping : std::vector<Damping>{{"none", 0.0, 0.0}, {"light", 0.1, 1e-4}, {"heavy", 5.0, 1e-2}}) {
    if (requested(options.dampings, damping.name)) grid.dampings.push_back(damping);
  }
  const std::vector<std::pair<std::string, std::string>> allIntegrators = {
      {"async", ""}, {"async", "symmetric"}, {"multirate-uncoupled", ""}, {"backward-euler", ""}};
  for (const auto& entry : allIntegrators) {
    const std::string name = entry.second.empty() ? entry.first : entry.first + "-" + entry.second;
    if (requested(options.integrators, name)) grid.integrators.push_back(entry);
  }
  for (const bool perturbed : {false, true}) {
    if (requested(options.meshes, perturbed ? "perturbed" : "regular")) grid.meshes.push_back(perturbed);
  }
  return grid;
}

// One case of the grid with the mesh file it runs on (written once per mesh).
struct Job {
  Case c;
  fs::path meshFile;
  double quality;
  std::vector<int> stiffVertices;  // the fast region of multirate cases
};

std::vector<Job> gridJobs(const Options& options, const Grid& grid, const fs::path& folder) {
  std::vector<Job> jobs;
  for (const double stiffnessRatio : grid.stiffnessRatios) {
    const BoxMeshSpec spec = barSpec(options, stiffnessRatio);
    for (const bool perturbed : grid.meshes) {
      double quality = 1.0;
      const TetMesh mesh = perturbed ? perturbedBar(spec, options.seed, &quality) : makeBoxMesh(spec);
      const fs::path meshFile =
          folder / ("bar-" + std::to_string(jobs.size()) + (perturbed ? "-perturbed" : "") + ".veg");
      writeVeg(meshFile, mesh);
      RegionSelector stiff;
      stiff.elementSets = {"stiff"};
      const std::vector<int> stiffVertices = regionVertices(mesh, stiff);
      for (const Damping& damping : grid.dampings) {
        for (const auto& [integrator, variant] : grid.integrators) {
          for (const int ratio : grid.ratios) {
            if (integrator == "backward-euler" && ratio != grid.ratios.front()) continue;  // m does not apply
            jobs.push_back({Case{integrator, variant, stiffnessRatio, ratio, damping, perturbed}, meshFile, quality,
                            stiffVertices});
          }
        }
      }
    }
  }
  return jobs;
}

// The table row and CSV line of a finished grid case; a blow-up or energy growth is added
// to problems.
void reportGridCase(const Job& job, const Outcome& o, int frames, std::ostream& csv,
                    std::vector<std::string>& problems) {
  const Case& c = job.c;
  const bool grows = o.energyGrowth > 1.0 + 1e-9;
  std::cout << "| " << c.integrator << (c.variant.empty() ? "" : " " + c.variant) << " | " << c.stiffnessRatio << " | "
            << (c.integrator == "backward-euler" ? std::string("-") : std::to_string(c.ratio)) << " | "
            << c.damping.name << " | "
            << (c.perturbed ? "perturbed (q " + std::to_string(job.quality).substr(0, 5) + ")" : "regular") << " | "
            << o.energyGrowth << " | " << (o.failedFrame < 0 ? std::string("-") : std::to_string(o.failedFrame))
            << " | " << o.maxDisplacement << " | " << std::fixed << std::setprecision(1) << o.seconds
            << std::defaultfloat << std::setprecision(6) << " |\n";
  std::cout.flush();
  csv << c.integrator << ',' << c.variant << ',' << c.stiffnessRatio << ',' << c.ratio << ',' << c.damping.name << ','
      << (c.perturbed ? "perturbed" : "regular") << ',' << frames << ',' << o.energyGrowth << ',' << o.failedFrame
      << ',' << o.maxDisplacement << ',' << o.seconds << ",\"" << o.failure << "\"\n";
  csv.flush();
  if (o.failedFrame >= 0) {
    problems.push_back("BLOW-UP: " + describe(c) + ": frame " + std::to_string(o.failedFrame) + ": " + o.failure);
  } else if (grows) {
    std::ostringstream line;
    line << "ENERGY GROWTH: " << describe(c) << ": max E/E0 = " << o.energyGrowth;
    problems.push_back(line.str());
  }
}

int run(const Options& options) {
  const int frames = options.full ? std::max(options.frames, 10000) : options.frames;
  const fs::path folder = fs::temp_directory_path() / ("asyncfem-stress-" + std::to_string(::getpid()));
  fs::create_directories(folder);
  const std::vector<Job> jobs = gridJobs(options, gridOf(options), folder);

  std::ofstream csv(options.csv);
  if (!csv) throw Error(options.csv + ": cannot open for writing");
  csv << "integrator,variant,stiffness_ratio,ratio,damping,mesh,frames,energy_growth,failed_frame,max_displacement,"
         "seconds,failure\n";
  const int workers = std::max(1, std::min<int>(options.jobs, static_cast<int>(jobs.size())));
  std::cout << "# stabilityStressTest: " << jobs.size() << " runs of " << frames
            << " frames (hL = 1/120, 30 frames per s), bar " << options.cells[0] << "x" << options.cells[1] << "x"
            << options.cells[2] << " cells, free vibration from a bent state, " << workers << " worker thread"
            << (workers > 1 ? "s" : "") << "\n\n";
  std::cout
      << "| integrator | stiffness ratio | m | damping | mesh | energy growth | first bad frame | max abs(u) | s |\n";
  std::cout << "|---|---|---|---|---|---|---|---|---|\n";

  std::vector<std::string> problems;
  Stopwatch total;
  runOrdered(
      jobs.size(), workers,
      [&](std::size_t index) {
        const Job& job = jobs[index];
        return runCase(job.c, job.meshFile, job.stiffVertices, frames);
      },
      [&](std::size_t index, const Outcome& o) { reportGridCase(jobs[index], o, frames, csv, problems); });
  std::cout << "\n"
            << jobs.size() << " runs in " << total.stop() << " s; " << problems.size()
            << " with a blow-up or energy growth (E/E0 > 1 + 1e-9)\n";
  for (const std::string& line : problems) std::cout << "- " << line << "\n";
  std::cout << "CSV: " << options.csv << "\n";
  fs::remove_all(folder);
  return 0;
}

// A number as the tables print it (6 significant digits).
std::string formatGrowth(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

// --scene: one run, an integrator from the --integrators list at one ratio m.
struct SceneJob {
  std::string integrator;
  int ratio;
};

std::vector<SceneJob> sceneJobs(const Options& options, const Scene& base) {
  const std::vector<int> ratios = chosen(options.ratios, {2, 4, 8, 16, 32, 64});
  const std::vector<std::string> integrators = chosen(
      options.integrators, {base.integrator.name == "async" ? "async" : "multirate-uncoupled", "backward-euler"});
  std::vector<SceneJob> jobs;
  for (const std::string& integrator : integrators) {
    for (const int ratio : ratios) {
      if (integrator == "backward-euler" && ratio != ratios.front()) continue;  // m does not apply
      jobs.push_back({integrator, ratio});
    }
  }
  return jobs;
}

// The scene's regions as the simulator reads them (the mesh and constraints only, nothing
// assembled).
std::vector<AsyncRegion> sceneRegions(const Scene& scene) {
  const std::shared_ptr<const Problem> problem = buildProblem(scene);
  const nlohmann::json regionsOnly = {{"regions", scene.integrator.options.at("regions")}};
  return parseAsyncOptions(scene, *problem->sharedMesh(), problem->freeDofs(), regionsOnly).regions;
}

// The scene of a job: every region's ratio set to the job's m, or backward Euler.
Scene sceneForJob(const Scene& base, std::vector<AsyncRegion> regions, const SceneJob& job, int frames) {
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
    for (const char* key : {"coupling", "schur", "method", "recovery", "substepContact"}) {
      scene.integrator.options.erase(key);
    }
  }
  return scene;
}

void reportSceneCase(const SceneJob& job, const Outcome& o, std::vector<std::string>& problems) {
  const std::string m = job.integrator == "backward-euler" ? std::string("-") : std::to_string(job.ratio);
  std::ostringstream estimate;  // "-" when the scene failed before the estimate
  if (o.stepGrowth) {
    estimate << formatGrowth(o.stepGrowth->spectralRadius) << (o.stepGrowth->converged ? "" : " (not converged)")
             << " | " << std::fixed << std::setprecision(1) << o.stepGrowth->seconds;
  } else {
    estimate << "- | -";
  }
  std::cout << "| " << job.integrator << " | " << m << " | " << estimate.str() << " | "
            << (o.energyMeasured ? formatGrowth(o.energyGrowth) : std::string("-")) << " | "
            << (o.failedFrame < 0 ? std::string("-") : std::to_string(o.failedFrame)) << " | " << o.maxDisplacement
            << " | " << std::fixed << std::setprecision(1) << o.seconds << std::defaultfloat << std::setprecision(6)
            << " |\n";
  std::cout.flush();
  const std::string what = job.integrator + (m == "-" ? "" : ", m = " + m);
  if (o.failedFrame >= 0) {
    problems.push_back("BLOW-UP: " + what + ": frame " + std::to_string(o.failedFrame) + ": " + o.failure);
  } else if (o.energyMeasured && o.energyGrowth > 1.0 + 1e-9) {
    std::ostringstream line;
    line << "ENERGY GROWTH: " << what << ": max E/E_free = " << o.energyGrowth;
    problems.push_back(line.str());
  }
}

// --scene: a user's multirate scene under several ratios m (every region's ratio set to
// m), and backward Euler at its large step, for its frames (or --frames); energy growth
// is measured once the loads are over.
int runScene(const Options& options) {
  const Scene base = loadScene(options.scene);
  const bool multirate = base.integrator.name == "async" || base.integrator.name == "multirate-uncoupled";
  if (!multirate || !base.integrator.options.contains("regions") || !base.integrator.options["regions"].is_array()) {
    throw Error(options.scene +
                ": integrator: --scene needs an \"async\" or \"multirate-uncoupled\" scene with explicit "
                "regions (not \"auto\")");
  }
  const int frames = options.framesGiven ? options.frames : base.timing.frameCount;
  const std::vector<AsyncRegion> regions = sceneRegions(base);
  const std::vector<SceneJob> jobs = sceneJobs(options, base);
  const int workers = std::max(1, std::min<int>(options.jobs, static_cast<int>(jobs.size())));
  std::cout
      << "# stabilityStressTest --scene " << options.scene << ": " << jobs.size() << " runs of " << frames
      << " frames, hL = " << base.timing.timestep
      << "; energy growth from when the last load window closes (not measured with contact); step growth "
         "estimate: spectral radius of one (large) step of the linearized scene, estimated from a few dozen "
         "steps before the run (its own seconds in \"estimate s\")"
      << "\n\n| integrator | m | step growth estimate | estimate s | energy growth | first bad frame | max abs(u) | s "
         "|\n|---|---|---|---|---|---|---|---|\n";
  std::vector<std::string> problems;
  Stopwatch total;
  runOrdered(
      jobs.size(), workers,
      [&](std::size_t index) {
        const Scene scene = sceneForJob(base, regions, jobs[index], frames);
        Simulation simulation = buildSimulation(scene);
        const StepGrowthEstimate stepGrowth = estimateSceneStepGrowth(scene, simulation);
        Outcome outcome = runSimulation(simulation, frames, simulation.monitor->energyCheckFrom());
        outcome.stepGrowth = stepGrowth;
        return outcome;
      },
      [&](std::size_t index, const Outcome& o) { reportSceneCase(jobs[index], o, problems); });
  std::cout << "\n"
            << jobs.size() << " runs in " << total.stop() << " s; " << problems.size()
            << " with a blow-up or energy growth (E/E_free > 1 + 1e-9)\n";
  for (const std::string& line : problems) std::cout << "- " << line << "\n";
  return problems.empty() ? 0 : 3;
}
}  // namespace

int main(int argc, char** argv) {
  asyncfem::preferPassiveThreadWaiting(argv);
  CLI::App app{"Stability stress test of the integrators (docs/benchmarks.md)"};
  Options options;
  app.add_option("--frames", options.frames, "Frames per run (default 100; --full: at least 10000)")
      ->check(asyncfem::cli::positive());
  app.add_flag("--full", options.full, "The full grid: 7 stiffness ratios, 6 timestep ratios, >= 10000 frames");
  app.add_option("--cells", options.cells, "Cells of the bar along x, y, z")->expected(3);
  app.add_option("--seed", options.seed, "Seed of the vertex perturbation");
  app.add_option("--csv", options.csv, "CSV output file (grid mode)");
  app.add_option("--scene", options.scene,
                 "Stress this async or multirate-uncoupled scene instead of the grid: every region's ratio set to each "
                 "--ratios value (default 2 4 8 16 32 64), plus backward Euler; exit status 3 when a run blows up or "
                 "gains energy after its loads end");
  app.add_option("--jobs", options.jobs, "Runs in parallel (each run is single-threaded work on a small mesh)")
      ->check(asyncfem::cli::positive());
  app.add_option("--stiffness-ratios", options.stiffnessRatios, "Only these stiffness ratios")
      ->check(asyncfem::cli::positive());
  app.add_option("--ratios", options.ratios, "Only these timestep ratios m")->check(asyncfem::cli::positive());
  app.add_option("--damping", options.dampings, "Only these damping levels")
      ->check(CLI::IsMember({"none", "light", "heavy"}));
  app.add_option("--integrators", options.integrators, "Only these integrators")
      ->check(CLI::IsMember({"async", "async-symmetric", "multirate-uncoupled", "backward-euler"}));
  app.add_option("--meshes", options.meshes, "Only these meshes")->check(CLI::IsMember({"regular", "perturbed"}));
  if (const std::optional<int> status = asyncfem::cli::parse(app, argc, argv, "stabilityStressTest")) return *status;
  options.framesGiven = app.count("--frames") > 0;
  return asyncfem::cli::run("stabilityStressTest",
                            [&] { return options.scene.empty() ? run(options) : runScene(options); });
}
