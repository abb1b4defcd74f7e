// SPDX-License-Identifier: BSD-3-Clause
// The configurations of the integrator benchmark: read from a file, from --config specs,
// or the default list for a scene.
#pragma once

#include <asyncfem/benchmarkTools/benchmarkRun.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <string>
#include <vector>

namespace asyncfem::bench {

/// Reads {"configurations": [{label, integrator, stepsPerFrame | timestep, ratio, options,
/// plot}, ...]}. "ratio" sets the ratio of every region of options.regions (taken from the
/// scene when the configuration gives no regions; resolved on baseline's mesh and written
/// back by the regions codec). Errors name the file and key.
std::vector<BenchmarkConfiguration> readConfigurations(const std::string& path, const Scene& scene,
                                                       const Simulation& baseline);
/// Parses "NAME[:key=value]..." with keys spf (steps per frame), dt, ratio, schur, method,
/// recovery, solver, label.
BenchmarkConfiguration parseConfigurationSpec(const std::string& spec, const Scene& scene, const Simulation& baseline);
/// The default list for a scene (documented in docs/benchmarks.md).
std::vector<BenchmarkConfiguration> defaultConfigurations(const Scene& scene, const Simulation& baseline);

/// The machine for reports: "nproc 2, Intel(R) ... (CPU model), load average 3.1 2.9 2.5".
std::string machineDescription();

}  // namespace asyncfem::bench
