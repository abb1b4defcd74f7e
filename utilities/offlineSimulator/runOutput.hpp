// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Where a Simulation's frames go: the .afsim file, the .vtu series and the checkpoint, new
// or continued from the checkpoint (--resume).

#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "commandLineOptions.hpp"
#include "runSummary.hpp"

namespace offline {

/// The scene file as the run fingerprint sees it: without frames.count and output, which
/// a resumed run may change (a Vega .config: the scene JSON it stands for).
std::string fingerprintText(const std::filesystem::path& sceneFile);

/// The folder of the output file, created if needed; an error names it and the cause.
void createOutputFolder(const std::filesystem::path& output);

/// A resumed run's .pvd lists the .vtu files of its earlier frames too, at the times
/// stored in the output file's records.
void listEarlierVtuFrames(const asyncfem::Scene& scene, int firstFrame, asyncfem::VtuSeriesWriter& series);

/// Where the frame loop writes: the .afsim file, the .vtu series, the checkpoint and its
/// bookkeeping.
struct RunOutput {
  asyncfem::SimulationFileHeader header;
  std::unique_ptr<asyncfem::SimulationWriter> writer;
  std::optional<asyncfem::VtuSeriesWriter> vtuSeries;
  std::uint32_t fingerprint = 0;
  std::filesystem::path checkpointFile;
  std::int64_t checkpointFrames = 0;  ///< frames the last checkpoint holds
  std::chrono::steady_clock::time_point lastCheckpoint = std::chrono::steady_clock::now();

  void checkpoint(const asyncfem::Simulation& simulation, std::int64_t frames, bool sync, RunRecord& record);
};

/// The output file's header for this run of scene.
asyncfem::SimulationFileHeader outputHeader(const CommandLine& options, const asyncfem::Scene& scene,
                                            const asyncfem::Simulation& simulation);

/// The run's fingerprint (asyncfem::runFingerprint) for this header.
std::uint32_t outputFingerprint(const CommandLine& options, const asyncfem::Scene& scene,
                                const asyncfem::Simulation& simulation, const asyncfem::SimulationFileHeader& header);

/// The output file is created (truncated) only once the scene has been built, so a scene
/// error leaves an existing file alone; from here on it holds this run's frames. A resumed
/// run continues the file from its checkpoint (restoring the simulation's state) and sets
/// record.firstFrame.
RunOutput openOutput(const CommandLine& options, const asyncfem::Scene& scene, asyncfem::Simulation& simulation,
                     RunRecord& record);

/// The frame's record, then (never ahead of the file) the checkpoint when due (or when a
/// stop signal came), and the .vtu file.
void writeFrame(RunOutput& output, const asyncfem::Scene& scene, const asyncfem::Simulation& simulation, int frame,
                RunRecord& record);

}  // namespace offline
