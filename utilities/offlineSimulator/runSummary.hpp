// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What offlineSimulator prints on stdout after a run: frames, mesh, model, the integrator's
// report, the time per frame phase by phase, what was skipped and checked, the output.

#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/runMonitor/runMonitor.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/sceneIO/stepGrowthCheck.hpp>
#include <cstdint>
#include <optional>
#include <string>

namespace offline {

/// What the summary reports about a run besides the simulation itself.
struct RunRecord {
  asyncfem::IntegratorStats before;  ///< the integrator's statistics after the set-up
  double setupSeconds = 0.0;
  double loopSeconds = 0.0;
  double outputSeconds = 0.0;
  std::int64_t outputBytes = 0;
  int firstFrame = 0;  ///< a resumed run starts after the frames already in the file
  std::optional<asyncfem::PaperCouplingCheck> couplingCheck;
  asyncfem::CheckpointSchedule schedule;
  int checkpointsWritten = 0;
};

/// "%9.3f ms" of seconds / frames.
std::string milliseconds(double seconds, int frames);

/// The run summary of a Simulation's run, on stdout.
void printSummary(const asyncfem::Scene& scene, const asyncfem::Simulation& simulation, const RunRecord& record);

}  // namespace offline
