// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// offlineSimulator --backend petsc (under mpiexec): the scene on the PETSc backend, every
// rank stepping, rank 0 writing the frames, through the one frame loop (frameLoop.hpp).

#include <asyncfem/sceneIO/scene.hpp>

#include "commandLineOptions.hpp"

namespace offline {

/// The scene's problem on PetscSimulation (every rank builds the problem): linear and
/// corotational backward Euler and trapezoidal, loads that depend on time only. Returns the
/// exit status.
int runPetsc(int argc, char** argv, const CommandLine& options, const asyncfem::Scene& scene);

/// The "async" integrator: every rank builds the scene's simulation and steps it on the
/// replicated state; L's system H^{LL*} is solved distributed, each fast region computed by
/// one rank (--petsc-regions replicated: by every rank). Returns the exit status.
int runPetscAsync(int argc, char** argv, const CommandLine& options, const asyncfem::Scene& scene);

}  // namespace offline
