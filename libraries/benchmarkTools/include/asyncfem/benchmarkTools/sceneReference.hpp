// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/benchmarkTools/modalReference.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <string>

namespace asyncfem {

/// Why a scene has no exact modal reference, or "" when it has one: corotational forces
/// (nonlinear), contact (state-dependent forces), or more than maxFreeDofs free DOFs (the
/// dense eigendecomposition would be too slow). The caller then falls back to a fine-step
/// trapezoidal run (design note, "What accurate means here").
std::string modalReferenceUnsupportedReason(const Scene& scene, const Simulation& simulation, int maxFreeDofs);

/// The scene's loads as an exact piecewise-constant load on simulation's mesh: gravity M g
/// from t = 0 (M: the integrator's mass matrix), each pull's total force split evenly over
/// its vertices during [start, end), each impulse as an instantaneous impulse at its time
/// (the integrators deliver it within the step after that time; the difference is part of
/// their error). Fixed DOFs are left in the vectors (the reference ignores them). Throws
/// asyncfem::ValidationError for an unknown vertex set (as buildSimulation would).
PiecewiseConstantLoad sceneLoad(const Scene& scene, const Simulation& simulation);

/// Frame times of a scene: (k + 1) / timing.frameRate for k = 0..count-1.
std::vector<double> frameTimes(const Scene& scene, int count);

}  // namespace asyncfem
