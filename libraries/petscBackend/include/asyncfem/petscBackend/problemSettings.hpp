// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/petscBackend/petscSimulation.hpp>
#include <asyncfem/problem/problem.hpp>
#include <string>

namespace asyncfem {

/// The PETSc backend's settings for a problem: the same Problem the single-process path
/// builds from a scene (buildProblem), stepped by the integrator named integratorName
/// ("backward-euler" or "trapezoidal") at timestep h (seconds). Takes the mass type,
/// Rayleigh damping, fixed vertices and gravity of the problem, and its load windows as
/// the time-dependent force; the solver is left at its defaults. Throws ValidationError
/// naming what the backend cannot run: contact (its forces depend on the state), force
/// models other than linear and corotational with the simple tangent, other integrators.
PetscSimulationSettings petscSettingsForProblem(const Problem& problem, const std::string& integratorName,
                                                double timestep);

}  // namespace asyncfem
