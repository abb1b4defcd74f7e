// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/integrator/integratorOptions.hpp>
#include <asyncfem/petscBackend/petscSimulation.hpp>
#include <asyncfem/problem/problem.hpp>
#include <string>

namespace asyncfem {

/// The PETSc backend's settings for a problem: the same Problem the single-process path
/// builds from a scene (buildProblem), stepped by the integrator named integratorName
/// ("backward-euler" or "trapezoidal") at timestep h (seconds), with the integrator's
/// options (petscNewtonSettings()). Takes the mass type, the force model with its
/// tangent kind and hyperelastic options, Rayleigh damping, fixed vertices and gravity
/// of the problem, and its load windows as the time-dependent force; the solver is left
/// at its defaults. Throws ValidationError naming what the backend cannot run: contact
/// (its forces depend on the state), other integrators, Newton iterations with the
/// trapezoidal rule, and what petscNewtonSettings() refuses.
PetscSimulationSettings petscSettingsForProblem(const Problem& problem, const std::string& integratorName,
                                                double timestep, const IntegratorOptions& options = {});

/// The backend's name of a problem's force model type (the same models). Never throws for
/// the types there are today (it throws ValidationError for an unknown value).
PetscForceModelKind petscForceModelKind(ForceModelType type);

/// The Newton settings of the single-process backward Euler's options: maxIterations,
/// tolerance and lineSearch. The options that choose the single-process linear solve
/// (solver, reuseFactor, pcgTolerance, pcgRefactorIterations) have no meaning here (the
/// PETSc solver replaces them) and are ignored. Throws ValidationError for
/// rayleighStiffnessAtIterate, which the backend does not run.
PetscNewtonSettings petscNewtonSettings(const IntegratorOptions& options);

}  // namespace asyncfem
