// SPDX-License-Identifier: BSD-3-Clause
// The frame timing: resolved once from a scene's keys, changed only through
// overrideFrameTiming, and the message that explains a timestep that does not divide the
// frame interval.
#include "detail/frameTiming.hpp"

#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/settings/jsonReader.hpp>
#include <cmath>
#include <sstream>
#include <string>

namespace asyncfem {

namespace detail {

namespace {

std::string formatNumber(double value, int precision = 6) {
  std::ostringstream out;
  out.precision(precision);
  out << value;
  return out.str();
}

// A duration 1 / (rate * steps) as "1/990 s" when rate is a whole number, else as a decimal.
std::string describeDuration(double rate, long long steps) {
  const double denominator = rate * static_cast<double>(steps);
  if (rate == std::round(rate) && denominator < 1e15) {
    return "1/" + std::to_string(static_cast<long long>(denominator)) + " s";
  }
  return formatNumber(1.0 / denominator, 9) + " s";
}

// "1/990 s = 0.0010101 (33 steps per frame)"
std::string describeDivisor(double rate, long long steps) {
  const std::string exact = describeDuration(rate, steps);
  const std::string decimal = formatNumber(1.0 / (rate * static_cast<double>(steps)), 9) + " s";
  return (exact == decimal ? exact : exact + " = " + decimal) + " (" + std::to_string(steps) +
         (steps == 1 ? " step" : " steps") + " per frame)";
}

// Relative paths in a scene are relative to the scene file's folder.
// Why the timestep h does not divide the frame interval 1 / rate into whole steps
// (ratio of them), with the valid timesteps nearest to it.
std::string describeTimestepMismatch(double rate, double h, double ratio) {
  std::string message = formatNumber(h, 9) + " does not divide the frame interval " + describeDuration(rate, 1) +
                        " (frames.rate " + formatNumber(rate, 9) + ") into whole steps: " + formatNumber(ratio, 12) +
                        " steps per frame; ";
  if (ratio > maxStepsPerFrame) {
    message += "the smallest timestep allowed is " + describeDivisor(rate, maxStepsPerFrame);
  } else if (ratio < 1.0) {
    message += "the timestep is longer than a frame; the longest valid timestep is " + describeDivisor(rate, 1);
  } else {
    const auto fewer = static_cast<long long>(std::floor(ratio));
    message +=
        "the nearest valid timesteps are " + describeDivisor(rate, fewer) + " and " + describeDivisor(rate, fewer + 1);
  }
  return message + "; or give the steps per frame instead (integrator.stepsPerFrame)";
}

}  // namespace

void checkTimingKeys(const TimingKeys& keys, const std::string& sourceName) {
  if (!(keys.frameRate > 0.0) || !std::isfinite(keys.frameRate)) {
    JsonObjectReader::failAt(sourceName, "frames.rate", "expected a number > 0");
  }
  if (keys.frameCount < 1) JsonObjectReader::failAt(sourceName, "frames.count", "expected a count >= 1");
  if (keys.stepsPerFrame > 0) return;
  if (!(keys.timestep > 0.0) || !std::isfinite(keys.timestep)) {
    JsonObjectReader::failAt(sourceName, "integrator.timestep", "expected a number > 0");
  }
}

FrameTiming divideFrameInterval(const TimingKeys& keys) {
  FrameTiming timing;
  timing.frameRate = keys.frameRate;
  timing.frameInterval = 1.0 / keys.frameRate;
  timing.frameCount = keys.frameCount;
  if (keys.stepsPerFrame > 0) {
    timing.stepsPerFrame = keys.stepsPerFrame;
    timing.timestep = timing.frameInterval / timing.stepsPerFrame;
    return timing;
  }
  timing.timestep = keys.timestep;
  const double ratio = timing.frameInterval / keys.timestep;
  const double steps = std::round(ratio);
  // |h - T / N| / (T / N) = |N - ratio| / ratio.
  if (steps >= 1.0 && steps <= maxStepsPerFrame && std::abs(ratio - steps) <= timestepDivisorTolerance * ratio) {
    timing.stepsPerFrame = static_cast<int>(steps);
  }
  return timing;
}

}  // namespace detail

FrameTiming resolveFrameTiming(const TimingKeys& keys, const std::string& sourceName) {
  detail::checkTimingKeys(keys, sourceName);
  FrameTiming timing = detail::divideFrameInterval(keys);
  if (!timing.resolved()) {
    JsonObjectReader::failAt(
        sourceName, "integrator.timestep",
        detail::describeTimestepMismatch(keys.frameRate, keys.timestep, timing.frameInterval / keys.timestep));
  }
  return timing;
}

const FrameTiming& requireFrameTiming(const Scene& scene) {
  if (!scene.timing.resolved()) {
    // Throws: the keys of an unresolved timing are its rate, count and written timestep.
    resolveFrameTiming({scene.timing.frameRate, scene.timing.frameCount, scene.timing.timestep, 0}, scene.sourceName);
  }
  return scene.timing;
}

void overrideFrameTiming(Scene& scene, const TimingOverrides& overrides) {
  if (overrides.timestep && overrides.stepsPerFrame) {
    throwSceneError(scene, "integrator", "give either a timestep or steps per frame, not both");
  }
  if (overrides.stepsPerFrame && *overrides.stepsPerFrame < 1) {
    throwSceneError(scene, "integrator.stepsPerFrame", "expected a count >= 1");
  }
  // The timing as keys: its timestep, which resolves to its own steps per frame again.
  TimingKeys keys{scene.timing.frameRate, scene.timing.frameCount, scene.timing.timestep, 0};
  if (overrides.frameRate) keys.frameRate = *overrides.frameRate;
  if (overrides.frameCount) keys.frameCount = *overrides.frameCount;
  if (overrides.timestep) keys.timestep = *overrides.timestep;
  if (overrides.stepsPerFrame) keys.stepsPerFrame = *overrides.stepsPerFrame;
  scene.timing = resolveFrameTiming(keys, scene.sourceName);
}

}  // namespace asyncfem
