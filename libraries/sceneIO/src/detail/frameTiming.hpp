// SPDX-License-Identifier: BSD-3-Clause
// The frame timing's resolution from a scene's keys (frames.rate, frames.count,
// integrator.timestep or integrator.stepsPerFrame), shared by the scene parser and the
// timing functions of scene.hpp. Private to the library.
#pragma once

#include <asyncfem/sceneIO/scene.hpp>
#include <string>

namespace asyncfem::detail {

/// Most steps per frame a scene may ask for.
inline constexpr int maxStepsPerFrame = 1000000000;

/// Throws asyncfem::ParseError naming the key for timing keys out of range: frames.rate or
/// frames.count, or a timestep that is not > 0 when no steps per frame are given.
void checkTimingKeys(const TimingKeys& keys, const std::string& sourceName);

/// The timing of keys that checkTimingKeys accepts; stepsPerFrame is left 0 (not resolved)
/// when the timestep does not divide the frame interval into whole steps.
FrameTiming divideFrameInterval(const TimingKeys& keys);

}  // namespace asyncfem::detail
