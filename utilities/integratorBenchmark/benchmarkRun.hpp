// SPDX-License-Identifier: BSD-3-Clause
// Configurations of the integrator benchmark and running one of them on a scene.
#pragma once

#include <asyncfem/benchmarkTools/errorMetrics.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace asyncfem::bench {

/// One integrator setting to measure. The timestep is either stepsPerFrame (h = frame
/// interval / stepsPerFrame, exact) or timestep.
struct Configuration {
  std::string label;
  std::string integrator = "backward-euler";          ///< registry name
  int stepsPerFrame = 0;                              ///< > 0: h = 1 / (rate stepsPerFrame)
  double timestep = 0.0;                              ///< used when stepsPerFrame is 0
  nlohmann::json options = nlohmann::json::object();  ///< integrator.options
  bool plotTrajectory = false;                        ///< draw its vertex curve in the trajectory plot
};

/// Multirate integrators (their options carry regions).
bool isMultirate(const std::string& integrator);

/// Reads {"configurations": [{label, integrator, stepsPerFrame | timestep, ratio, options,
/// plot}, ...]}. "ratio" sets the ratio of every region of options.regions (taken from the
/// scene when the configuration gives no regions). Errors name the file and key.
std::vector<Configuration> readConfigurations(const std::string& path, const Scene& scene);
/// Parses "NAME[:key=value]..." with keys spf (steps per frame), dt, ratio, schur, method,
/// recovery, solver, label.
Configuration parseConfigurationSpec(const std::string& spec, const Scene& scene);
/// The default list for a scene (documented in docs/benchmarks.md).
std::vector<Configuration> defaultConfigurations(const Scene& scene, const Simulation& baseline);

/// The scene with the configuration's integrator, timestep, options and frame count.
Scene configuredScene(const Scene& scene, const Configuration& configuration, int frames);

struct RunResult {
  Configuration configuration;
  double timestep = 0.0;  ///< h (large step for multirate)
  int stepsPerFrame = 0;
  std::string ratios;  ///< "8" or "8,4" for multirate, "" otherwise
  bool completed = false;
  int failedFrame = -1;  ///< first frame that failed (non-finite or blow-up), -1 if none
  std::string failure;
  Trajectory frames;                    ///< displacement after every completed frame
  std::vector<double> secondsPerFrame;  ///< one per repeat: mean over frames 1.. (frame 0 is warm-up)
  double medianSecondsPerFrame = 0.0;
  double minSecondsPerFrame = 0.0;
  double setupSeconds = 0.0;       ///< building the simulation (first repeat)
  double firstFrameSeconds = 0.0;  ///< frame 0 (factorizations of linear models happen there)
  // Per frame over frames 1.. (machine independent, from IntegratorStats).
  double factorizationsPerFrame = 0.0, solvesPerFrame = 0.0, factorFlopsPerFrame = 0.0, solveFlopsPerFrame = 0.0;
  long long factorNonZeros = -1;         ///< multirate integrators only
  std::map<std::string, double> errors;  ///< per vertex group
  double flopsPerFrame() const { return factorFlopsPerFrame + solveFlopsPerFrame; }
};

/// Builds and runs the configuration `repeats` times (frames each); the trajectory and the
/// costs come from the first repeat, the time per frame is the median over repeats. A
/// NumericalError (non-finite state, blow-up: advanceFrame's checks) ends the run and is
/// recorded, never thrown; scene errors are thrown.
RunResult runConfiguration(const Scene& scene, const Configuration& configuration, int frames, int repeats);

/// The machine for reports: "nproc 2, Intel(R) ... (CPU model), load average 3.1 2.9 2.5".
std::string machineDescription();

/// Median of a non-empty list (mean of the two middle values for an even count); 0 if empty.
double median(std::vector<double> values);

/// "1/120" style text for a timestep that divides the frame interval, else "%g".
std::string formatTimestep(double timestep);

}  // namespace asyncfem::bench
