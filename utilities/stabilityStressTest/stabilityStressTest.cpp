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
// The grid, the runs and the verdict are library benchmarkTools' (stabilityStress.hpp); this
// program reads the options and prints the table. docs/benchmarks.md lists the grid and
// the results.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <asyncfem/benchmarkTools/stabilityStress.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/sceneIO/stepGrowthCheck.hpp>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "commandLine.hpp"

namespace {

namespace fs = std::filesystem;
using namespace asyncfem;

struct Options {
  int frames = 100;
  std::vector<int> cells{8, 2, 2};
  unsigned seed = 1;
  std::string csv = "stability.csv";
  std::string scene;         // --scene: stress a user's scene instead of the built-in grid
  bool framesGiven = false;  // --frames was on the command line
  int jobs = 1;
  StressGridSelection grid;  // --full and the lists that narrow the grid (--scene: ratios, integrators)
};

std::string describe(const StressCase& c) {
  std::ostringstream out;
  out << c.integrator << (c.variant.empty() ? "" : " " + c.variant) << ", stiffness ratio " << c.stiffnessRatio;
  if (c.integrator != "backward-euler") out << ", m = " << c.ratio;
  out << ", damping " << c.damping.name << ", " << (c.perturbed ? "perturbed" : "regular") << " mesh";
  return out.str();
}

// The selection lists the user can narrow: an empty list means the default.
template <typename T>
std::vector<T> chosen(const std::vector<T>& requested, std::vector<T> defaults) {
  return requested.empty() ? defaults : requested;
}

// The line of the closing list for a run that blew up or gained energy (stabilityVerdict);
// empty for a stable one. energyRatio: how the growth is named (E/E0, E/E_free).
std::string problemLine(const std::string& what, const StressOutcome& o, const std::string& energyRatio) {
  std::ostringstream line;
  switch (stabilityVerdict(o)) {
    case StabilityVerdict::blowUp:
      line << "BLOW-UP: " << what << ": frame " << o.failedFrame << ": " << o.failure;
      break;
    case StabilityVerdict::energyGrowth:
      line << "ENERGY GROWTH: " << what << ": max " << energyRatio << " = " << o.energyGrowth;
      break;
    case StabilityVerdict::stable:
      break;
  }
  return line.str();
}

// The table row and CSV line of a finished grid case; a blow-up or energy growth is added
// to problems.
void reportGridCase(const StressJob& job, const StressOutcome& o, int frames, std::ostream& csv,
                    std::vector<std::string>& problems) {
  const StressCase& c = job.stressCase;
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
  if (const std::string line = problemLine(describe(c), o, "E/E0"); !line.empty()) problems.push_back(line);
}

int run(const Options& options) {
  const int frames = options.grid.full ? std::max(options.frames, 10000) : options.frames;
  const fs::path folder = fs::temp_directory_path() / ("asyncfem-stress-" + std::to_string(::getpid()));
  fs::create_directories(folder);
  const Eigen::Vector3i cells(options.cells[0], options.cells[1], options.cells[2]);
  const std::vector<StressJob> jobs = stressJobs(stressGrid(options.grid), cells, options.seed, folder);

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
  runStressJobsInOrder(
      jobs.size(), workers, [&](std::size_t index) { return runStressJob(jobs[index], frames); },
      [&](std::size_t index, const StressOutcome& o) { reportGridCase(jobs[index], o, frames, csv, problems); });
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

void reportSceneCase(const SceneStressJob& job, const StressOutcome& o, std::vector<std::string>& problems) {
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
  if (const std::string line = problemLine(what, o, "E/E_free"); !line.empty()) problems.push_back(line);
}

// --scene: a user's multirate scene under several ratios m (every region's ratio set to
// m), and backward Euler at its large step, for its frames (or --frames); energy growth
// is measured once the loads are over.
int runScene(const Options& options) {
  const Scene base = loadScene(options.scene);
  const std::vector<AsyncRegion> regions = sceneStressRegions(base);
  const int frames = options.framesGiven ? options.frames : base.timing.frameCount;
  const std::vector<SceneStressJob> jobs =
      sceneStressJobs(chosen(options.grid.integrators,
                             {base.integrator.name == "async" ? "async" : "multirate-uncoupled", "backward-euler"}),
                      chosen(options.grid.ratios, {2, 4, 8, 16, 32, 64}));
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
  runStressJobsInOrder(
      jobs.size(), workers,
      [&](std::size_t index) {
        const Scene scene = sceneForStressJob(base, regions, jobs[index], frames);
        Simulation simulation = buildSimulation(scene);
        const StepGrowthEstimate stepGrowth = estimateSceneStepGrowth(scene, simulation);
        StressOutcome outcome = runStressFrames(simulation, frames, simulation.monitor->energyCheckFrom());
        outcome.stepGrowth = stepGrowth;
        return outcome;
      },
      [&](std::size_t index, const StressOutcome& o) { reportSceneCase(jobs[index], o, problems); });
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
  app.add_flag("--full", options.grid.full, "The full grid: 7 stiffness ratios, 6 timestep ratios, >= 10000 frames");
  app.add_option("--cells", options.cells, "Cells of the bar along x, y, z")->expected(3);
  app.add_option("--seed", options.seed, "Seed of the vertex perturbation");
  app.add_option("--csv", options.csv, "CSV output file (grid mode)");
  app.add_option("--scene", options.scene,
                 "Stress this async or multirate-uncoupled scene instead of the grid: every region's ratio set to each "
                 "--ratios value (default 2 4 8 16 32 64), plus backward Euler; exit status 3 when a run blows up or "
                 "gains energy after its loads end");
  app.add_option("--jobs", options.jobs, "Runs in parallel (each run is single-threaded work on a small mesh)")
      ->check(asyncfem::cli::positive());
  app.add_option("--stiffness-ratios", options.grid.stiffnessRatios, "Only these stiffness ratios")
      ->check(asyncfem::cli::positive());
  app.add_option("--ratios", options.grid.ratios, "Only these timestep ratios m")->check(asyncfem::cli::positive());
  app.add_option("--damping", options.grid.dampings, "Only these damping levels")
      ->check(CLI::IsMember({"none", "light", "heavy"}));
  app.add_option("--integrators", options.grid.integrators, "Only these integrators")
      ->check(CLI::IsMember({"async", "async-symmetric", "multirate-uncoupled", "backward-euler"}));
  app.add_option("--meshes", options.grid.meshes, "Only these meshes")->check(CLI::IsMember({"regular", "perturbed"}));
  if (const std::optional<int> status = asyncfem::cli::parse(app, argc, argv, "stabilityStressTest")) return *status;
  options.framesGiven = app.count("--frames") > 0;
  return asyncfem::cli::run("stabilityStressTest",
                            [&] { return options.scene.empty() ? run(options) : runScene(options); });
}
