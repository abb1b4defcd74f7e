// SPDX-License-Identifier: BSD-3-Clause
#include "runOutput.hpp"

#include <asyncfem/core/error.hpp>
#include <asyncfem/runMonitor/runMonitor.hpp>
#include <asyncfem/sceneIO/vegaConfig.hpp>
#include <asyncfem/simulationIO/checkpoint.hpp>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

#include "stopSignal.hpp"

namespace offline {

namespace fs = std::filesystem;

std::string fingerprintText(const fs::path& sceneFile) {
  nlohmann::json json = asyncfem::sceneFileJson(sceneFile);
  if (json.is_object()) {
    json.erase("output");
    if (json.contains("frames") && json["frames"].is_object()) json["frames"].erase("count");
  }
  return json.dump();
}

void createOutputFolder(const fs::path& output) {
  if (!output.has_parent_path()) return;
  std::error_code error;
  fs::create_directories(output.parent_path(), error);
  if (error) {
    throw asyncfem::Error(output.parent_path().string() + ": cannot create the output folder: " + error.message());
  }
}

void listEarlierVtuFrames(const asyncfem::Scene& scene, int firstFrame, asyncfem::VtuSeriesWriter& series) {
  asyncfem::SimulationReader reader(scene.output.file);
  for (int k = 0; k < firstFrame && k < reader.numFrames(); k += scene.output.vtuEvery) {
    if (fs::exists(series.folder() / asyncfem::VtuSeriesWriter::frameFileName(k))) {
      series.addExistingFrame(k, reader.readFrame(k).time);
    }
  }
}

void RunOutput::checkpoint(const asyncfem::Simulation& simulation, std::int64_t frames, bool sync, RunRecord& record) {
  const asyncfem::RunMonitor* monitor = simulation.monitor ? &*simulation.monitor : nullptr;
  asyncfem::writeCheckpoint(checkpointFile,
                            asyncfem::captureCheckpoint(*simulation.integrator, frames, fingerprint, monitor), sync);
  checkpointFrames = frames;
  ++record.checkpointsWritten;
  lastCheckpoint = std::chrono::steady_clock::now();
}

asyncfem::SimulationFileHeader outputHeader(const CommandLine& options, const asyncfem::Scene& scene,
                                            const asyncfem::Simulation& simulation) {
  asyncfem::SimulationFileHeader header;
  header.numVertices = simulation.mesh->numVertices();
  header.frameInterval = simulation.timing.frameInterval;
  header.timestep = simulation.integrator->timestep();
  header.hasVelocities = scene.output.velocities;
  // The scene, so that frameRenderer and afsimTool find the mesh by themselves.
  header.scenePath = fs::weakly_canonical(fs::absolute(options.scene)).string();
  header.sceneFingerprint = asyncfem::problemFingerprint(*simulation.problem);
  asyncfem::describeRegionOutput(scene, simulation, header);        // output.regions: the fast regions of each frame
  asyncfem::describeContactForceOutput(scene, simulation, header);  // output.contactForces
  return header;
}

std::uint32_t outputFingerprint(const CommandLine& options, const asyncfem::Scene& scene,
                                const asyncfem::Simulation& simulation, const asyncfem::SimulationFileHeader& header) {
  return asyncfem::runFingerprint(fingerprintText(options.scene), scene.integrator.name, header.timestep,
                                  header.frameInterval, *simulation.problem);
}

RunOutput openOutput(const CommandLine& options, const asyncfem::Scene& scene, asyncfem::Simulation& simulation,
                     RunRecord& record) {
  createOutputFolder(scene.output.file);
  RunOutput output;
  if (!scene.output.vtuFolder.empty()) output.vtuSeries.emplace(scene.output.vtuFolder, scene.output.vtuEncoding);
  output.header = outputHeader(options, scene, simulation);
  const asyncfem::SimulationWriter::Options writerOptions{scene.output.sync};
  output.fingerprint = outputFingerprint(options, scene, simulation, output.header);
  output.checkpointFile = asyncfem::checkpointPathFor(scene.output.file);
  if (options.resume) {
    record.firstFrame = static_cast<int>(asyncfem::resumeFromCheckpoint(
        scene.output.file, output.header, output.fingerprint, simulation.timing.frameCount, *simulation.integrator,
        simulation.monitor ? &*simulation.monitor : nullptr));
    output.writer =
        asyncfem::SimulationWriter::continueFile(scene.output.file, output.header, record.firstFrame, writerOptions);
    const std::string caveat = simulation.integrator->report().resumeCaveat;
    if (!caveat.empty() && !options.quiet) std::printf("resume: %s\n", caveat.c_str());
  } else {
    output.writer = std::make_unique<asyncfem::SimulationWriter>(scene.output.file, output.header, writerOptions);
    // The rest state, so that a run stopped before its first frame can be resumed too.
    asyncfem::writeCheckpoint(output.checkpointFile,
                              asyncfem::captureCheckpoint(*simulation.integrator, 0, output.fingerprint),
                              scene.output.sync);
  }
  output.checkpointFrames = record.firstFrame;
  if (output.vtuSeries) {
    if (record.firstFrame > 0) listEarlierVtuFrames(scene, record.firstFrame, *output.vtuSeries);
    output.vtuSeries->writeCollection();
  }
  return output;
}

void writeFrame(RunOutput& output, const asyncfem::Scene& scene, const asyncfem::Simulation& simulation, int frame,
                RunRecord& record) {
  const asyncfem::Integrator& integrator = *simulation.integrator;
  const bool vtuFrame = output.vtuSeries && frame % scene.output.vtuEvery == 0;
  // The contact forces once, for the record and the .vtu.
  Eigen::VectorXd forces;
  if (scene.output.contactForces) forces = asyncfem::contactForces(simulation);
  asyncfem::appendSimulationFrame(*output.writer, simulation, scene.output.contactForces ? &forces : nullptr);
  const int done = frame + 1;
  const double sinceLast =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - output.lastCheckpoint).count();
  if (record.schedule.due(done, sinceLast) || done == simulation.timing.frameCount || stopSignal() != 0) {
    output.checkpoint(simulation, done, scene.output.sync, record);
  }
  if (vtuFrame) {
    std::vector<asyncfem::VtuArray> pointArrays;
    if (scene.output.contactForces) {
      pointArrays.push_back({"contactForce", 3, std::vector<double>(forces.data(), forces.data() + forces.size())});
    }
    output.vtuSeries->writeFrame(frame, integrator.time(), *simulation.mesh, integrator.displacement(), pointArrays);
  }
}

}  // namespace offline
