// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/benchmarkTools/benchmarkRun.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/integrator/multirateIntegrator.hpp>
#include <asyncfem/sceneIO/asyncScene.hpp>
#include <cmath>
#include <optional>
#include <sstream>

namespace asyncfem {

bool isMultirate(const std::string& integrator) {
  return integrator == "async" || integrator == "multirate-uncoupled" || integrator == "schroeder2011";
}

Scene configuredScene(const Scene& scene, const BenchmarkConfiguration& configuration, int frames) {
  Scene out = scene;
  out.integrator.name = configuration.integrator;
  out.integrator.options = configuration.options;
  TimingOverrides timing;
  if (configuration.stepsPerFrame > 0) {
    timing.stepsPerFrame = configuration.stepsPerFrame;
  } else {
    timing.timestep = configuration.timestep;
  }
  timing.frameCount = frames;
  overrideFrameTiming(out, timing);
  out.output = Scene::OutputSettings{};
  return out;
}

std::vector<AsyncRegion> configurationRegions(const Scene& scene, const Simulation& baseline,
                                              const BenchmarkConfiguration& configuration) {
  if (!isMultirate(configuration.integrator)) return {};
  nlohmann::json options = configuration.options;
  // The other multirate integrators' own keys; the regions are read as async reads them.
  for (const char* key : {"compoundSolver", "rigidity", "force"}) options.erase(key);
  return parseAsyncOptions(configuredScene(scene, configuration, 1), *baseline.mesh,
                           baseline.integrator->system().freeDofs, options)
      .regions;
}

namespace {

struct Repeat {
  double seconds = 0.0;  // over frames 1..
  int timedFrames = 0;
  bool failed = false;
};

// One timed pass over the frames; the first repeat records the trajectory, the failure and
// the machine-independent costs into result.
Repeat timedRepeat(const Scene& configured, int frames, bool first, BenchmarkRun& result) {
  Stopwatch setup;
  Repeat repeat;
  std::optional<Simulation> built;
  try {
    built.emplace(buildSimulation(configured));
  } catch (const TimestepError& error) {
    // A step the integrator refuses (schroeder2011's substeps above their explicit
    // limit): reported as a configuration that fails before its first frame.
    if (first) {
      result.failedFrame = 0;
      result.failure = error.what();
    }
    repeat.failed = true;
    return repeat;
  }
  Simulation& simulation = *built;
  const double setupSeconds = setup.stop();
  Integrator& integrator = *simulation.integrator;
  IntegratorStats afterWarmUp;
  for (int frame = 0; frame < frames; ++frame) {
    Stopwatch watch;
    try {
      advanceFrame(simulation, frame);
    } catch (const NumericalError& error) {
      if (first) {
        result.failedFrame = frame;
        result.failure = error.what();
      }
      repeat.failed = true;
      break;
    }
    const double seconds = watch.stop();
    if (frame == 0) {
      // Warm-up: linear models factor here; excluded from the time per frame.
      afterWarmUp = integrator.stats();
      if (first) result.firstFrameSeconds = seconds;
    } else {
      repeat.seconds += seconds;
      ++repeat.timedFrames;
    }
    if (first) result.frames.push_back(integrator.displacement());
  }
  if (first) {
    result.setupSeconds = setupSeconds;
    const IntegratorStats& end = integrator.stats();
    const double count = std::max(1, repeat.timedFrames);
    result.factorizationsPerFrame = static_cast<double>(end.factorizations - afterWarmUp.factorizations) / count;
    result.solvesPerFrame = static_cast<double>(end.solvedRightHandSides - afterWarmUp.solvedRightHandSides) / count;
    result.factorFlopsPerFrame = (end.factorFlops - afterWarmUp.factorFlops) / count;
    result.solveFlopsPerFrame = (end.solveFlops - afterWarmUp.solveFlops) / count;
    result.factorNonZeros = integrator.report().factorNonZeros;
    for (const RegionSummary& region : regionSummaries(integrator)) result.ratios.push_back(region.ratio);
  }
  return repeat;
}

}  // namespace

BenchmarkRun runConfiguration(const Scene& scene, const BenchmarkConfiguration& configuration, int frames,
                              int repeats) {
  BenchmarkRun result;
  result.configuration = configuration;
  const Scene configured = configuredScene(scene, configuration, frames);
  result.timestep = configured.timing.timestep;
  result.stepsPerFrame = configured.timing.stepsPerFrame;
  for (int repeat = 0; repeat < std::max(1, repeats); ++repeat) {
    const Repeat timed = timedRepeat(configured, frames, repeat == 0, result);
    if (timed.failed) break;  // an unstable configuration is not timed again
    if (timed.timedFrames > 0) result.secondsPerFrame.push_back(timed.seconds / timed.timedFrames);
  }
  result.completed = result.failedFrame < 0;
  if (!result.secondsPerFrame.empty()) {
    result.medianSecondsPerFrame = median(result.secondsPerFrame);
    result.minSecondsPerFrame = *std::min_element(result.secondsPerFrame.begin(), result.secondsPerFrame.end());
  }
  return result;
}

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

std::string formatTimestep(double timestep) {
  const double inverse = 1.0 / timestep;
  const double rounded = std::round(inverse);
  std::ostringstream out;
  if (rounded >= 1.0 && std::abs(inverse - rounded) <= 1e-9 * inverse) {
    out << "1/" << static_cast<long long>(rounded);
  } else {
    out << timestep;
  }
  return out.str();
}

std::string formatRatios(const std::vector<int>& ratios) {
  std::ostringstream out;
  for (std::size_t i = 0; i < ratios.size(); ++i) out << (i ? "," : "") << ratios[i];
  return out.str();
}

}  // namespace asyncfem
