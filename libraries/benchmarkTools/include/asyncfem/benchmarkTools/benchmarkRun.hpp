// SPDX-License-Identifier: BSD-3-Clause
// One integrator configuration of a benchmark, and running it on a scene.
#pragma once

#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/benchmarkTools/errorMetrics.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace asyncfem {

/// One integrator setting to measure. The timestep is either stepsPerFrame (h = frame
/// interval / stepsPerFrame, exact) or timestep (s).
struct BenchmarkConfiguration {
  std::string label;
  std::string integrator = "backward-euler";          ///< registry name
  int stepsPerFrame = 0;                              ///< > 0: h = frame interval / stepsPerFrame
  double timestep = 0.0;                              ///< used when stepsPerFrame is 0
  nlohmann::json options = nlohmann::json::object();  ///< integrator.options
  bool plotTrajectory = false;                        ///< draw its vertex curve in the trajectory plot
};

/// Multirate integrators (their options carry regions): "async", "multirate-uncoupled" and
/// "schroeder2011".
bool isMultirate(const std::string& integrator);

/// The scene with the configuration's integrator, options, timestep and frame count (its
/// timing resolved again by overrideFrameTiming, whose ValidationError it throws for a
/// timestep that does not divide the frame interval), and no output.
Scene configuredScene(const Scene& scene, const BenchmarkConfiguration& configuration, int frames);

/// The fast regions a multirate configuration runs with, resolved on baseline's mesh and
/// free DOFs as the integrator resolves them (parseAsyncSettings: explicit regions, or the
/// region proposal at the configuration's step); empty for a single-rate integrator.
/// Throws what parseAsyncSettings throws for bad regions.
std::vector<AsyncRegion> configurationRegions(const Scene& scene, const Simulation& baseline,
                                              const BenchmarkConfiguration& configuration);

/// What running one configuration measured.
struct BenchmarkRun {
  BenchmarkConfiguration configuration;
  double timestep = 0.0;  ///< h (s); the large step for multirate
  int stepsPerFrame = 0;
  std::vector<int> ratios;  ///< m_i of every region of a multirate run, in order; empty otherwise
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
  long long factorNonZeros = -1;         ///< the integrator's kept factors (RunReport::factorNonZeros)
  std::map<std::string, double> errors;  ///< relative L2 error per vertex group name (filled by the caller)
  double flopsPerFrame() const { return factorFlopsPerFrame + solveFlopsPerFrame; }
};

/// Builds and runs the configuration `repeats` times (frames each); the trajectory and the
/// costs come from the first repeat, the time per frame is the median over repeats. A
/// NumericalError (non-finite state, blow-up: advanceFrame's checks) ends the run and is
/// recorded, never thrown; scene errors are thrown.
BenchmarkRun runConfiguration(const Scene& scene, const BenchmarkConfiguration& configuration, int frames, int repeats);

/// Median of a list (mean of the two middle values for an even count); 0 if empty.
double median(std::vector<double> values);

/// "1/120" style text for a timestep (s) whose inverse is a whole number, else "%g".
std::string formatTimestep(double timestep);

/// Ratios as the tables print them: "8" or "8,4"; "" for none.
std::string formatRatios(const std::vector<int>& ratios);

}  // namespace asyncfem
