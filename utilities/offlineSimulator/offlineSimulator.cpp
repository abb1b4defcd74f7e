// SPDX-License-Identifier: BSD-3-Clause
// offlineSimulator: runs a scene file and stores its frames.
//
//   offlineSimulator SCENE.json [--output FILE.afsim] [--integrator NAME] [--dt H]
//                    [--frames N] [--vtu FOLDER] [--resume] [--checkpoint-every K]
//                    [--progress] [--quiet] [--no-stability-check]
//
// Frames go to one .afsim file (docs/simulation-output.md), optionally one .vtu per
// frame; progress on stderr, the run summary on stdout. After every K-th frame (default
// every frame) the full state goes to FILE.afsim.checkpoint, so that --resume continues
// an interrupted run and produces exactly the file an uninterrupted run would have.
// SIGINT and SIGTERM stop the run after the current frame, with a checkpoint, and exit
// with status 128 + the signal number (--backend petsc: every rank stops after the same
// frame; rank 0 writes the checkpoint, every rank restores it with --resume). A scene that runs the asynchronous
// integrator with the paper's coupling gets its step growth estimated before the run (a few dozen steps of the
// linearized scene) and a warning when a large step can grow. Errors print "offlineSimulator: <message>" on stderr and
// exit with status 1. What it prints is described in docs/scene-format.md, section "Running a scene".
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/integrator/multirateIntegrator.hpp>
#include <asyncfem/runMonitor/runMonitor.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/sceneObjects.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/sceneIO/stepGrowthCheck.hpp>
#include <asyncfem/sceneIO/vegaConfig.hpp>
#include <asyncfem/simulationIO/checkpoint.hpp>
#include <asyncfem/simulationIO/crc32.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <bit>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#if ASYNCFEM_OFFLINE_WITH_PETSC
#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/integrator/registry.hpp>
#include <asyncfem/petscBackend/largeSystemSolver.hpp>
#include <asyncfem/petscBackend/petscRuntime.hpp>
#include <asyncfem/petscBackend/petscSimulation.hpp>
#include <asyncfem/petscBackend/problemSettings.hpp>
#include <asyncfem/petscBackend/rankSummedForceModel.hpp>
#endif

#include "commandLine.hpp"
#include "progress.hpp"

namespace {

namespace fs = std::filesystem;

struct CommandLine {
  std::string scene;
  std::optional<std::string> output;
  std::optional<std::string> integrator;
  std::optional<double> timestep;
  std::optional<int> stepsPerFrame;
  std::optional<int> frames;
  std::optional<std::string> vtuFolder;
  bool resume = false;
  int checkpointEvery = 0;
  double checkpointSeconds = 30.0;
  bool progress = false;
  bool quiet = false;
  bool noStabilityCheck = false;
  std::string backend = "local";
  std::string petscSolver = "cg-gamg";
  std::string petscOptions;
  std::string petscRegions = "owned";
  std::string petscElements = "distributed";
};

// The signal that asked the run to stop (0: none). A signal handler can only set a flag
// of this type, so this one piece of state is global; the loop polls it between frames.
volatile std::sig_atomic_t stopSignal = 0;

extern "C" void requestStop(int signal) {
  stopSignal = signal;
  // write() is async-signal-safe; the handler was installed with SA_RESETHAND, so a
  // second signal ends the process at once (finished frames are safe either way).
  static constexpr char message[] =
      "\nofflineSimulator: stopping after the current frame (send the signal again to stop at once)\n";
  const ssize_t ignored = ::write(STDERR_FILENO, message, sizeof(message) - 1);
  static_cast<void>(ignored);
}

void installStopHandlers() {
  struct sigaction action {};
  action.sa_handler = requestStop;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;
  ::sigaction(SIGINT, &action, nullptr);
  ::sigaction(SIGTERM, &action, nullptr);
}

const char* signalName(int signal) {
  switch (signal) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    default:
      return "a signal";
  }
}

// The scene file as the run fingerprint sees it: without frames.count and output, which
// a resumed run may change (a Vega .config: the scene JSON it stands for).
std::string fingerprintText(const fs::path& sceneFile) {
  nlohmann::json json = asyncfem::sceneFileJson(sceneFile);
  if (json.is_object()) {
    json.erase("output");
    if (json.contains("frames") && json["frames"].is_object()) json["frames"].erase("count");
  }
  return json.dump();
}

// The command to continue an interrupted run: this one, with --resume added.
std::string resumeCommand(int argc, char** argv) {
  std::string command;
  bool hasResume = false;
  for (int i = 0; i < argc; ++i) {
    const std::string argument = argv[i];
    hasResume = hasResume || argument == "--resume";
    if (i > 0) command += ' ';
    if (!argument.empty() &&
        argument.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_./=+:,") ==
            std::string::npos) {
      command += argument;
    } else {
      command += '\'';
      for (const char c : argument) {
        if (c == '\'') {
          command += "'\\''";
        } else {
          command += c;
        }
      }
      command += '\'';
    }
  }
  if (!hasResume) command += " --resume";
  return command;
}

// The folder of the output file, created if needed; an error names it and the cause.
void createOutputFolder(const fs::path& output) {
  if (!output.has_parent_path()) return;
  std::error_code error;
  fs::create_directories(output.parent_path(), error);
  if (error) {
    throw asyncfem::Error(output.parent_path().string() + ": cannot create the output folder: " + error.message());
  }
}

// Command-line values replace the scene's; paths given here are relative to the
// current folder, not the scene's.
void applyOverrides(const CommandLine& options, asyncfem::Scene& scene) {
  if (options.output) {
    scene.output.file = *options.output;
  }
  if (options.integrator) {
    const std::vector<std::string> dropped =
        asyncfem::switchIntegrator(scene, asyncfem::defaultIntegratorRegistry(), *options.integrator);
    if (!dropped.empty()) {
      std::string list;
      for (const std::string& key : dropped) list += (list.empty() ? "" : ", ") + key;
      std::cerr << "offlineSimulator: --integrator " << *options.integrator
                << ": dropped the scene's integrator.options " << list << " (not read by " << *options.integrator
                << ")\n";
    }
  }
  asyncfem::overrideFrameTiming(scene, {options.timestep, options.stepsPerFrame, options.frames});
  if (options.vtuFolder) {
    scene.output.vtuFolder = *options.vtuFolder;
  } else if (options.output && !scene.output.vtuFolder.empty()) {
    // The scene's .vtu series follows --output (OUT.afsim -> OUT_vtu/), so that two runs
    // of one scene with different outputs do not write one series over the other.
    fs::path folder = *options.output;
    folder.replace_extension();
    folder += "_vtu";
    scene.output.vtuFolder = folder;
  }
  if (scene.output.file.empty()) {
    throw asyncfem::Error("no output file: set output.file in " + scene.sourceName + " or pass --output FILE");
  }
}

// Refuses an output (the .afsim file or its checkpoint) that is one of the run's inputs:
// truncating it would destroy the scene or mesh before the run could read it again.
void refuseOutputsOverInputs(const CommandLine& options, const asyncfem::Scene& scene) {
  std::vector<asyncfem::cli::NamedPath> inputs{{"the scene", options.scene}};
  if (scene.mesh.source == asyncfem::Scene::MeshSource::file) inputs.push_back({"the mesh", scene.mesh.file});
  if (scene.fixed.bouFile) inputs.push_back({"the fixed-vertex file", *scene.fixed.bouFile});
  const std::string advice = "choose another output (--output or output.file)";
  asyncfem::cli::refuseOutputOverInputs({"the output file", scene.output.file}, inputs, advice);
  asyncfem::cli::refuseOutputOverInputs({"the checkpoint file", asyncfem::checkpointPathFor(scene.output.file)}, inputs,
                                        advice);
}

/// A resumed run's .pvd lists the .vtu files of its earlier frames too, at the times
/// stored in the output file's records.
void listEarlierVtuFrames(const asyncfem::Scene& scene, int firstFrame, asyncfem::VtuSeriesWriter& series) {
  asyncfem::SimulationReader reader(scene.output.file);
  for (int k = 0; k < firstFrame && k < reader.numFrames(); k += scene.output.vtuEvery) {
    if (fs::exists(series.folder() / asyncfem::VtuSeriesWriter::frameFileName(k))) {
      series.addExistingFrame(k, reader.readFrame(k).time);
    }
  }
}

std::string milliseconds(double seconds, int frames) {
  char text[32];
  std::snprintf(text, sizeof(text), "%9.3f ms", 1000.0 * seconds / frames);
  return text;
}

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

// The first lines: frames and steps, mesh, model, regions, integrator report, set-up and
// the stability estimate. Leaves out fixed with precision 3.
void printRunHeader(std::ostream& out, const asyncfem::Scene& scene, const asyncfem::Simulation& simulation,
                    const RunRecord& record) {
  const asyncfem::FrameTiming& timing = simulation.timing;
  const std::optional<asyncfem::PaperCouplingCheck>& couplingCheck = record.couplingCheck;
  out << "offlineSimulator: " << scene.sourceName << ": " << (timing.frameCount - record.firstFrame) << " frames";
  if (record.firstFrame > 0) {
    out << " (resumed after frame " << record.firstFrame << " of " << timing.frameCount << ")";
  }
  out << ", " << (simulation.integrator->stats().steps - record.before.steps) << " steps of h = " << std::defaultfloat
      << std::setprecision(9) << simulation.integrator->timestep() << std::setprecision(3) << " ("
      << timing.stepsPerFrame << " per frame), " << std::fixed
      << (record.setupSeconds + record.loopSeconds + (couplingCheck ? couplingCheck->estimate.seconds : 0.0)) << " s\n";
  out << "  mesh        " << simulation.mesh->numVertices() << " vertices, " << simulation.mesh->numElements()
      << " elements, " << simulation.fixedVertices.size() << " fixed vertices\n";
  out << "  model       " << asyncfem::toString(simulation.problem->settings().forceModel)
      << (scene.forceModel != asyncfem::Scene::ForceModelKind::corotational ? ""
          : scene.tangent == asyncfem::Scene::Tangent::exact                ? " (exact tangent)"
                                                                            : " (simple tangent)")
      << ", " << (scene.mass == asyncfem::MassType::lumped ? "lumped" : "consistent") << " mass, integrator "
      << simulation.integrator->name() << "\n";
  const std::vector<asyncfem::RegionSummary> regions = asyncfem::regionSummaries(*simulation.integrator);
  if (!regions.empty()) {
    out << "  regions     " << regions.size() << " fast region" << (regions.size() == 1 ? "" : "s") << " (the rest, L, "
        << "steps at h):\n";
    for (std::size_t i = 0; i < regions.size(); ++i) {
      const asyncfem::RegionSummary& region = regions[i];
      out << "    S_" << (i + 1) << " '" << region.name << "': " << region.vertices << " vertices, "
          << region.interfaceDofs << " interface DOFs, m = " << region.ratio << " (h / " << region.ratio << ")\n";
    }
  }
  for (const std::string& line : simulation.integrator->report().lines) out << "  integrator  " << line << "\n";
  for (const std::string& line : asyncfem::surfaceContactSummary(simulation)) out << "  contact     " << line << "\n";
  out << "  setup       " << record.setupSeconds
      << " s (mesh, matrices, first factorization: " << record.before.factorizationSeconds << " s)\n";
  if (couplingCheck) {
    const asyncfem::StepGrowthEstimate& estimate = couplingCheck->estimate;
    out << "  stability   paper coupling, " << couplingCheck->regions << ": step growth estimate " << std::defaultfloat
        << std::setprecision(6) << estimate.spectralRadius << std::setprecision(3)
        << (estimate.converged ? "" : " (not converged)") << " from " << estimate.steps
        << " steps of the linearized scene, " << std::fixed << estimate.seconds << " s"
        << (couplingCheck->warning.empty() ? "" : " (WARNING above)") << "\n";
  }
}

// The frame loop's time per frame, phase by phase (this run's share of the statistics).
void printFrameTimes(std::ostream& out, const asyncfem::Simulation& simulation, const RunRecord& record) {
  const asyncfem::IntegratorStats& after = simulation.integrator->stats();
  const asyncfem::IntegratorStats& before = record.before;
  // Frames computed by this run (a resumed run starts at firstFrame).
  const int frames = std::max(simulation.timing.frameCount - record.firstFrame, 1);
  const double forces = after.forceSeconds - before.forceSeconds;
  const double assembly = after.assemblySeconds - before.assemblySeconds;
  const double factorization = after.factorizationSeconds - before.factorizationSeconds;
  const double solve = after.solveSeconds - before.solveSeconds;
  const double loopSeconds = record.loopSeconds;
  const double other = loopSeconds - forces - assembly - factorization - solve - record.outputSeconds;
  out << "  per frame   " << milliseconds(loopSeconds, frames) << "   (total " << loopSeconds << " s)\n";
  out << "    forces        " << milliseconds(forces, frames) << "\n";
  out << "    assembly      " << milliseconds(assembly, frames) << "\n";
  out << "    factorization " << milliseconds(factorization, frames) << "   ("
      << (after.factorizations - before.factorizations) << " factorizations in the run)\n";
  out << "    solve         " << milliseconds(solve, frames) << "   ("
      << (after.solvedRightHandSides - before.solvedRightHandSides) << " right-hand sides)\n";
  out << "    output        " << milliseconds(record.outputSeconds, frames) << "\n";
  if (other >= 0.0) {
    out << "    other         " << milliseconds(other, frames) << "   (vector updates, loads, state checks)\n";
  } else {
    // Phases timed on several threads at once (the regions of an asynchronous step, the
    // blocks of Z) add up to more than the wall time: there is no remainder to show.
    out << "    other                 -   (the phases above ran on several threads at once: their times add up to "
        << std::setprecision(3) << 1000.0 * (loopSeconds - other) / frames
        << " ms per frame, more than the wall time)\n";
  }
}

// What was skipped, what was checked, and where the output went.
void printRunTrailer(std::ostream& out, const asyncfem::Scene& scene, const asyncfem::Simulation& simulation,
                     const RunRecord& record) {
  out << "  skipped:\n";
  for (const std::string& item : simulation.integrator->stats().skipped) {
    out << "    - " << item << "\n";
  }
  for (const std::string& item : simulation.skipped) {
    out << "    - " << item << "\n";
  }
  const long long evaluations = simulation.monitor->energyEvaluations();
  out << "  checks      finite state and blow-up after every step; energy "
      << (evaluations > 0 ? std::to_string(evaluations) + " evaluations (once per frame after the loads)"
                          : std::string("not evaluated (see skipped)"))
      << "\n";
  out << "  output      " << scene.output.file.string() << " (" << simulation.timing.frameCount << " frames, "
      << record.outputBytes << " bytes; " << record.checkpointsWritten << " checkpoints, " << record.schedule.describe()
      << " and at the end, in " << asyncfem::checkpointPathFor(scene.output.file).string() << ")";
  if (!scene.output.vtuFolder.empty()) {
    out << ", .vtu files in " << scene.output.vtuFolder.string();
  }
  out << "\n";
}

void printSummary(const asyncfem::Scene& scene, const asyncfem::Simulation& simulation, const RunRecord& record) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(3);
  printRunHeader(out, scene, simulation, record);
  printFrameTimes(out, simulation, record);
  printRunTrailer(out, scene, simulation, record);
  std::cout << out.str() << std::flush;
}

#if ASYNCFEM_OFFLINE_WITH_PETSC
const std::string petscPrefix = "--backend petsc: ";

// The backend's settings for the scene's problem (asyncfem::petscSettingsForProblem) and
// its integrator's options (Newton iterations), with the solver chosen on the command line.
asyncfem::PetscSimulationSettings petscSettings(const CommandLine& options, const asyncfem::Scene& scene,
                                                const asyncfem::Problem& problem) {
  asyncfem::PetscSimulationSettings settings;
  try {
    const std::string& name = scene.integrator.name;
    const asyncfem::IntegratorOptions integratorOptions =
        name == "backward-euler" || name == "trapezoidal"
            ? asyncfem::parseIntegratorOptions(scene.integrator.options, "integrator.options", scene.sourceName)
            : asyncfem::IntegratorOptions{};
    settings = asyncfem::petscSettingsForProblem(problem, name, scene.timing.timestep, integratorOptions);
  } catch (const asyncfem::ValidationError& error) {
    throw asyncfem::Error(petscPrefix + scene.sourceName + ": " + error.what());
  }
  settings.solver.kind = asyncfem::parsePetscSolverKind(options.petscSolver);
  return settings;
}

void printPetscSummary(const asyncfem::Scene& scene, const asyncfem::PetscRunStats& stats, double setupSeconds,
                       double loopSeconds) {
  const asyncfem::FrameTiming& timing = scene.timing;
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(3);
  out << "offlineSimulator: " << scene.sourceName << ": " << timing.frameCount << " frames, " << stats.steps
      << " steps of h = " << std::defaultfloat << timing.timestep << std::fixed << " on the PETSc backend, "
      << (setupSeconds + loopSeconds) << " s\n";
  out << "  ranks       " << stats.ranks << " (" << stats.freeDofs << " free DOFs, " << stats.matrixNonZeros
      << " matrix non-zeros; KSP " << stats.kspType << ", PC " << stats.pcType << ")\n";
  out << "  setup       " << setupSeconds << " s\n";
  out << "  per frame   " << milliseconds(loopSeconds, timing.frameCount) << "   (assembly " << stats.assemblySeconds
      << " s, solves " << stats.solveSeconds << " s, " << stats.solverIterations << " iterations in " << stats.solves
      << " solves)\n";
  if (stats.newtonIterations > stats.steps) {
    out << "  newton      " << stats.newtonIterations << " iterations in " << stats.steps << " steps\n";
  }
  out << "  output      " << scene.output.file.string() << " (" << timing.frameCount << " frames; checkpoint in "
      << asyncfem::checkpointPathFor(scene.output.file).string() << ")\n";
  std::cout << out.str() << std::flush;
}

// The output of a PETSc run: rank 0 writes the frames, the .vtu series and the checkpoint
// (writer and vtuSeries are empty on the other ranks); every rank gathers the state for a
// checkpoint and, with output.velocities, for each frame. The checkpoint names the
// integrator with " (PETSc)", so that a local run does not resume it, nor this one a local one.
struct PetscOutput {
  std::unique_ptr<asyncfem::SimulationWriter> writer;
  std::optional<asyncfem::VtuSeriesWriter> vtuSeries;
  const asyncfem::TetMesh* mesh = nullptr;
  int vtuEvery = 1;
  asyncfem::SimulationFileHeader header;
  fs::path checkpointFile;
  std::uint32_t fingerprint = 0;
  std::string integrator;
  asyncfem::CheckpointSchedule schedule;
  bool sync = false;
  int checkpointFrames = 0;
  std::chrono::steady_clock::time_point lastCheckpoint = std::chrono::steady_clock::now();

  // Collective: the state after `frames` finished frames, written by rank 0.
  void checkpoint(const asyncfem::PetscSimulation& simulation, int frames) {
    asyncfem::SimulationCheckpoint state;
    state.displacement = simulation.gatherDisplacement();
    state.velocity = simulation.gatherVelocity();
    state.internalState = simulation.gatherInternalState();
    if (simulation.rank() == 0) {
      state.frames = frames;
      state.time = simulation.time();
      state.fingerprint = fingerprint;
      state.integrator = integrator;
      asyncfem::writeCheckpoint(checkpointFile, state, sync);
    }
    checkpointFrames = frames;
    lastCheckpoint = std::chrono::steady_clock::now();
  }
  // Collective: whether rank 0's schedule asks for a checkpoint after `frames` frames.
  bool due(const asyncfem::PetscRuntime& runtime, int frames, int frameCount) const {
    const double since = std::chrono::duration<double>(std::chrono::steady_clock::now() - lastCheckpoint).count();
    const bool wanted = frames == frameCount || schedule.due(frames, since);
    return runtime.maxOverRanks(runtime.rank() == 0 && wanted ? 1 : 0) != 0;
  }
};

// Opens the output of a PETSc run: a new file with the rest state's checkpoint, or with
// --resume the run's file continued after the frames its checkpoint has (every rank reads
// and checks the checkpoint, restores its state, and all agree before going on). Returns
// the frames already finished.
int openPetscOutput(const CommandLine& options, const asyncfem::Scene& scene, const asyncfem::Problem& problem,
                    const asyncfem::PetscRuntime& runtime, asyncfem::PetscSimulation& simulation, PetscOutput& output) {
  const asyncfem::FrameTiming& timing = scene.timing;
  output.header.numVertices = problem.mesh().numVertices();
  output.header.frameInterval = timing.frameInterval;
  output.header.timestep = simulation.timestep();
  output.header.hasVelocities = scene.output.velocities;
  output.header.scenePath = fs::weakly_canonical(fs::absolute(options.scene)).string();
  output.header.sceneFingerprint = asyncfem::problemFingerprint(problem);
  output.checkpointFile = asyncfem::checkpointPathFor(scene.output.file);
  output.fingerprint = asyncfem::runFingerprint(fingerprintText(options.scene), scene.integrator.name,
                                                output.header.timestep, output.header.frameInterval, problem);
  output.integrator = scene.integrator.name + " (PETSc)";
  output.schedule = asyncfem::CheckpointSchedule{options.checkpointEvery, options.checkpointSeconds};
  output.sync = scene.output.sync;
  const bool root = runtime.rank() == 0;
  const asyncfem::SimulationWriter::Options writerOptions{scene.output.sync};
  output.mesh = &problem.mesh();
  output.vtuEvery = scene.output.vtuEvery;
  if (root && !scene.output.vtuFolder.empty()) {
    output.vtuSeries.emplace(scene.output.vtuFolder, scene.output.vtuEncoding);
  }
  if (!options.resume) {
    if (root) {
      createOutputFolder(scene.output.file);
      output.writer = std::make_unique<asyncfem::SimulationWriter>(scene.output.file, output.header, writerOptions);
      if (output.vtuSeries) output.vtuSeries->writeCollection();
    }
    output.checkpoint(simulation, 0);  // the rest state: a run stopped before its first frame resumes too
    return 0;
  }
  asyncfem::SimulationCheckpoint checkpoint;
  std::string failure;
  try {
    checkpoint = asyncfem::checkpointToResume(scene.output.file, output.header, output.fingerprint, timing.frameCount,
                                              output.integrator, problem.numDofs());
  } catch (const asyncfem::Error& error) {
    failure = error.what();
  }
  if (runtime.maxOverRanks(failure.empty() ? 0 : 1) != 0) {
    throw asyncfem::Error(failure.empty() ? "cannot resume: another rank could not use the checkpoint" : failure);
  }
  simulation.setState(checkpoint.displacement, checkpoint.velocity, checkpoint.time);
  simulation.setInternalState(checkpoint.internalState);
  const auto frames = static_cast<int>(checkpoint.frames);
  if (root) {
    output.writer = asyncfem::SimulationWriter::continueFile(scene.output.file, output.header, frames, writerOptions);
    if (output.vtuSeries) {
      if (frames > 0) listEarlierVtuFrames(scene, frames, *output.vtuSeries);
      output.vtuSeries->writeCollection();
    }
  }
  output.checkpointFrames = frames;
  return frames;
}

// The frame loop of a PETSc run from firstFrame: every rank steps, rank 0 writes each frame
// and draws the progress; checkpoints as scheduled (rank 0's clock decides). A stop signal
// that reached any rank stops every rank before the same frame (one MPI_Allreduce per
// frame), so no rank waits for the others in a collective call. Returns the frames completed.
int runPetscFrames(const CommandLine& options, const asyncfem::Scene& scene, const asyncfem::PetscRuntime& runtime,
                   asyncfem::PetscSimulation& simulation, PetscOutput& output, int firstFrame) {
  const asyncfem::FrameTiming& timing = scene.timing;
  const bool root = simulation.rank() == 0;
  asyncfem::cli::ProgressReporter progress(
      "offlineSimulator",
      root ? asyncfem::cli::chooseProgressStyle(options.quiet, options.progress) : asyncfem::cli::ProgressStyle::none,
      timing.frameCount, firstFrame);
  int frame = firstFrame;
  try {
    for (; frame < timing.frameCount && runtime.maxOverRanks(static_cast<int>(stopSignal)) == 0; ++frame) {
      for (int s = 0; s < timing.stepsPerFrame; ++s) simulation.step();  // non-finite states throw on every rank
      const Eigen::VectorXd u = simulation.gatherDisplacement();
      if (output.header.hasVelocities) {
        const Eigen::VectorXd v = simulation.gatherVelocity();  // collective, like the gather above
        if (root) output.writer->appendFrame(simulation.time(), u, v);
      } else if (root) {
        output.writer->appendFrame(simulation.time(), u);
      }
      if (root && output.vtuSeries && frame % output.vtuEvery == 0) {
        output.vtuSeries->writeFrame(frame, simulation.time(), *output.mesh, u);
      }
      if (output.due(runtime, frame + 1, timing.frameCount)) output.checkpoint(simulation, frame + 1);
      progress.update(frame + 1);
    }
  } catch (const asyncfem::Error& error) {
    progress.finish();
    throw asyncfem::Error(std::string(error.what()) + "; the " + std::to_string(frame) +
                          " frames before it are kept in " + scene.output.file.string());
  }
  progress.finish();
  if (frame != output.checkpointFrames) output.checkpoint(simulation, frame);  // stopped by a signal
  return frame;
}

// --backend petsc: the scene's problem on the PETSc backend (every rank builds the problem,
// rank 0 writes the frames). Supports what that backend integrates: linear and
// corotational backward Euler and trapezoidal, loads that depend on time only.
int runPetsc(int argc, char** argv, const CommandLine& options, const asyncfem::Scene& scene) {
  asyncfem::Stopwatch setupWatch;
  setupWatch.start();
  asyncfem::PetscRuntime runtime(&argc, &argv, options.petscOptions);
  const asyncfem::FrameTiming& timing = scene.timing;
  std::vector<std::string> warnings;
  const std::shared_ptr<const asyncfem::Problem> problem = asyncfem::buildProblem(scene, &warnings);
  asyncfem::PetscSimulation simulation(problem->mesh(), petscSettings(options, scene, *problem));
  const bool root = simulation.rank() == 0;
  if (root) {
    for (const std::string& warning : warnings) std::cerr << "offlineSimulator: warning: " << warning << "\n";
  }
  PetscOutput output;
  const int firstFrame = openPetscOutput(options, scene, *problem, runtime, simulation, output);
  const double setupSeconds = setupWatch.stop();
  installStopHandlers();  // after PETSc's start, whose own handlers it replaces for these signals
  asyncfem::Stopwatch loopWatch;
  loopWatch.start();
  const int frames = runPetscFrames(options, scene, runtime, simulation, output, firstFrame);
  const double loopSeconds = loopWatch.stop();
  if (root) output.writer->close();
  const int signal = runtime.maxOverRanks(static_cast<int>(stopSignal));
  if (signal != 0 && frames < timing.frameCount) {
    if (root) {
      std::cerr << "offlineSimulator: interrupted by " << signalName(signal) << ": " << frames << " of "
                << timing.frameCount << " frames are complete in " << scene.output.file.string()
                << " (checkpoint after frame " << output.checkpointFrames << " in " << output.checkpointFile.string()
                << "); continue the run with:\n  mpiexec -n " << runtime.size() << " " << resumeCommand(argc, argv)
                << "\n";
    }
    return 128 + signal;
  }
  if (root && !options.quiet) printPetscSummary(scene, simulation.stats(), setupSeconds, loopSeconds);
  return 0;
}
#endif

void addSceneOptions(CLI::App& app, CommandLine& options) {
  app.add_option("scene", options.scene, "Scene file (.json)")->required();
  app.add_option("-o,--output", options.output,
                 "Output .afsim file (replaces output.file; truncated at the start of the run)");
  app.add_option("--integrator", options.integrator, "Integrator name (replaces integrator.name)");
  auto* timestep = app.add_option("--dt", options.timestep,
                                  "Timestep h (replaces integrator.timestep); must divide the frame interval "
                                  "1 / frames.rate to a relative 1e-9")
                       ->check(asyncfem::cli::positive());
  app.add_option("--steps-per-frame", options.stepsPerFrame,
                 "Steps per frame N, so h = (1 / frames.rate) / N (replaces integrator.timestep or "
                 "integrator.stepsPerFrame)")
      ->check(asyncfem::cli::atLeast(1))
      ->excludes(timestep);
  app.add_option("--frames", options.frames, "Number of frames (replaces frames.count)")
      ->check(asyncfem::cli::atLeast(1));
  app.add_option("--vtu", options.vtuFolder,
                 "Also write FOLDER/frame_NNNNN.vtu per frame (replaces output.vtu.folder)");
}

void addRunOptions(CLI::App& app, CommandLine& options) {
  app.add_flag("--resume", options.resume,
               "Continue the output file from its last checkpoint instead of starting over; the result is "
               "bit-identical to an uninterrupted run (frames.count / --frames may be raised)");
  app.add_option("--checkpoint-every", options.checkpointEvery,
                 "Also write the checkpoint (OUTPUT.checkpoint) every K frames (default: by time only); a resumed "
                 "run recomputes the frames after the last checkpoint")
      ->check(asyncfem::cli::atLeast(1));
  app.add_option("--checkpoint-seconds", options.checkpointSeconds,
                 "Write the checkpoint when this many seconds of wall time have passed since the last one "
                 "(default 30; 0: only by --checkpoint-every); the last frame and an interrupted run always get one")
      ->check(asyncfem::cli::atLeast(0.0));
  app.add_flag("--progress", options.progress, "Draw the progress bar even when stderr is not a terminal");
  app.add_flag("-q,--quiet", options.quiet, "Print nothing but errors");
  app.add_flag("--no-stability-check", options.noStabilityCheck,
               "Skip the step-growth estimate (a few dozen steps) made before runs of the asynchronous integrator "
               "with the paper's coupling");
  app.add_option("--backend", options.backend,
                 "Where the scene runs: local (default) or petsc (PETSc over MPI: run under mpiexec -n N; "
                 "backward-euler or trapezoidal, every force model; docs/petsc-backend.md)")
      ->check(CLI::IsMember({"local", "petsc"}))
      ->capture_default_str();
  app.add_option("--petsc-solver", options.petscSolver, "With --backend petsc: cg-gamg, cg-hypre or mumps")
      ->capture_default_str();
  app.add_option("--petsc-options", options.petscOptions,
                 "With --backend petsc: PETSc options database entries, e.g. \"-ksp_rtol 1e-10 -ksp_monitor\"");
  app.add_option("--petsc-regions", options.petscRegions,
                 "With --backend petsc and the async integrator: owned (each fast region computed by one rank, "
                 "the default) or replicated (every rank computes every region)")
      ->check(CLI::IsMember({"owned", "replicated"}))
      ->capture_default_str();
  app.add_option("--petsc-elements", options.petscElements,
                 "With --backend petsc and the async integrator: distributed (each rank evaluates the nonlinear "
                 "forces and tangent of its elements, summed over the ranks; the default) or replicated (every "
                 "rank evaluates every element)")
      ->check(CLI::IsMember({"distributed", "replicated"}))
      ->capture_default_str();
}

/// Where the frame loop writes: the .afsim file, the .vtu series, the checkpoint and its
/// bookkeeping.
struct RunOutput {
  asyncfem::SimulationFileHeader header;
  std::unique_ptr<asyncfem::SimulationWriter> writer;
  std::optional<asyncfem::VtuSeriesWriter> vtuSeries;
  std::uint32_t fingerprint = 0;
  fs::path checkpointFile;
  std::int64_t checkpointFrames = 0;  ///< frames the last checkpoint holds
  std::chrono::steady_clock::time_point lastCheckpoint = std::chrono::steady_clock::now();

  void checkpoint(const asyncfem::Simulation& simulation, std::int64_t frames, bool sync, RunRecord& record) {
    const asyncfem::RunMonitor* monitor = simulation.monitor ? &*simulation.monitor : nullptr;
    asyncfem::writeCheckpoint(checkpointFile,
                              asyncfem::captureCheckpoint(*simulation.integrator, frames, fingerprint, monitor), sync);
    checkpointFrames = frames;
    ++record.checkpointsWritten;
    lastCheckpoint = std::chrono::steady_clock::now();
  }
};

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
  asyncfem::describeRegionOutput(scene, simulation, header);  // output.regions: the fast regions of each frame
  return header;
}

// The output file is created (truncated) only once the scene has been built, so a scene
// error leaves an existing file alone; from here on it holds this run's frames. A resumed
// run continues the file from its checkpoint and sets record.firstFrame.
RunOutput openOutput(const CommandLine& options, const asyncfem::Scene& scene, asyncfem::Simulation& simulation,
                     RunRecord& record) {
  createOutputFolder(scene.output.file);
  RunOutput output;
  if (!scene.output.vtuFolder.empty()) output.vtuSeries.emplace(scene.output.vtuFolder, scene.output.vtuEncoding);
  output.header = outputHeader(options, scene, simulation);
  const asyncfem::SimulationWriter::Options writerOptions{scene.output.sync};
  output.fingerprint =
      asyncfem::runFingerprint(fingerprintText(options.scene), scene.integrator.name, output.header.timestep,
                               output.header.frameInterval, *simulation.problem);
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

// The frame's record, then (never ahead of the file) the checkpoint when due, and the .vtu file.
void writeFrame(RunOutput& output, const asyncfem::Scene& scene, const asyncfem::Simulation& simulation, int frame,
                RunRecord& record) {
  const asyncfem::Integrator& integrator = *simulation.integrator;
  asyncfem::appendSimulationFrame(*output.writer, simulation);
  const int done = frame + 1;
  const double sinceLast =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - output.lastCheckpoint).count();
  if (record.schedule.due(done, sinceLast) || done == simulation.timing.frameCount || stopSignal != 0) {
    output.checkpoint(simulation, done, scene.output.sync, record);
  }
  if (output.vtuSeries && frame % scene.output.vtuEvery == 0) {
    output.vtuSeries->writeFrame(frame, integrator.time(), *simulation.mesh, integrator.displacement());
  }
}

// Runs the frames from record.firstFrame until the last one or a stop signal; returns the
// frame it stopped at. A failing frame's error names the frames kept in the file.
int runFrames(const CommandLine& options, const asyncfem::Scene& scene, asyncfem::Simulation& simulation,
              RunOutput& output, RunRecord& record) {
  asyncfem::cli::ProgressReporter progress("offlineSimulator",
                                           asyncfem::cli::chooseProgressStyle(options.quiet, options.progress),
                                           simulation.timing.frameCount, record.firstFrame);
  asyncfem::Stopwatch loopWatch;
  asyncfem::Stopwatch outputWatch;
  loopWatch.start();
  int frame = record.firstFrame;
  try {
    for (; frame < simulation.timing.frameCount && stopSignal == 0; ++frame) {
      asyncfem::advanceFrame(simulation, frame);
      {
        const asyncfem::ScopedTimer timer(outputWatch);
        writeFrame(output, scene, simulation, frame, record);
      }
      progress.update(frame + 1);
    }
  } catch (const asyncfem::Error& error) {
    progress.finish();
    // A storage fault closed the file, and its message says what the file holds.
    if (!output.writer->isOpen()) throw;
    // The frames before the failing one are complete, checksummed records.
    throw asyncfem::Error(std::string(error.what()) + "; the " + std::to_string(output.writer->numFrames()) +
                          " frames before it are kept in " + scene.output.file.string());
  }
  record.loopSeconds = loopWatch.stop();
  record.outputSeconds = outputWatch.totalSeconds();
  progress.finish();
  return frame;
}

// The scene on this process: build, estimate the step growth, run the frames, report.
int runLocal(int argc, char** argv, const CommandLine& options, const asyncfem::Scene& scene,
             asyncfem::Stopwatch& setupWatch) {
  asyncfem::Simulation simulation = asyncfem::buildSimulation(scene);
  for (const std::string& warning : simulation.warnings) std::cerr << "offlineSimulator: warning: " << warning << "\n";
  RunRecord record;
  record.setupSeconds = setupWatch.stop();
  record.before = simulation.integrator->stats();
  record.schedule = asyncfem::CheckpointSchedule{options.checkpointEvery, options.checkpointSeconds};
  // On a separate integrator built for the linearized scene: the run's own state and
  // statistics are untouched.
  if (!options.noStabilityCheck) record.couplingCheck = asyncfem::checkPaperCoupling(scene, simulation);
  if (record.couplingCheck && !record.couplingCheck->warning.empty()) {
    std::cerr << "offlineSimulator: warning: " << record.couplingCheck->warning << "\n";
  }
  RunOutput output = openOutput(options, scene, simulation, record);
  installStopHandlers();
  const int frame = runFrames(options, scene, simulation, output, record);
  if (stopSignal != 0 && output.checkpointFrames != output.writer->numFrames()) {
    // The signal came after the last frame's checkpoint decision.
    output.checkpoint(simulation, output.writer->numFrames(), scene.output.sync, record);
  }
  output.writer->close();
  if (stopSignal != 0 && frame < simulation.timing.frameCount) {
    std::cerr << "offlineSimulator: interrupted by " << signalName(stopSignal) << ": " << output.writer->numFrames()
              << " of " << simulation.timing.frameCount << " frames are complete in " << scene.output.file.string()
              << " (checkpoint after frame " << output.checkpointFrames << " in " << output.checkpointFile.string()
              << "); continue the run with:\n  " << resumeCommand(argc, argv) << "\n";
    return 128 + static_cast<int>(stopSignal);
  }
  if (!options.quiet) {
    record.outputBytes = static_cast<std::int64_t>(fs::file_size(scene.output.file));
    printSummary(scene, simulation, record);
  }
  return 0;
}

#if ASYNCFEM_OFFLINE_WITH_PETSC
// --backend petsc with the "async" integrator: every rank builds the scene's simulation and
// steps the asynchronous integrator on the replicated state; L's system H^{LL*} is solved
// distributed (makePetscLargeSystemSolver), and each fast region is computed by one rank
// (makePetscRegionDistribution; --petsc-regions replicated: by every rank). Rank 0 writes the frames, checkpoints and
// the summary. The ranks agree once per frame on a stop signal and on rank 0's output failing, so none is left waiting
// in a collective call.
asyncfem::IntegratorRegistry petscAsyncRegistry(const CommandLine& options, const asyncfem::Scene& scene,
                                                std::shared_ptr<asyncfem::PetscSolveCounts> totals) {
  asyncfem::PetscSolverSettings solver;
  solver.kind = asyncfem::parsePetscSolverKind(options.petscSolver);
  // The L solve is one part of a step whose other parts are exact to round-off.
  solver.relativeTolerance = 1e-10;
  asyncfem::IntegratorRegistry registry = asyncfem::defaultIntegratorRegistry();
  const bool owned = options.petscRegions == "owned";
  asyncfem::registerMultirateIntegrators(
      registry, [solver, totals, owned](asyncfem::AsyncSettings& settings, const asyncfem::IntegratorContext& context) {
        // What the backend's solvers need of the options and the partition (stable coupling,
        // structured method, regions that do not touch) is checked where every option is:
        // chooseStepSolver(), which names the refused option.
        settings.solver.largeSystemSolver = asyncfem::makePetscLargeSystemSolver(*context.mesh, solver, totals);
        if (owned) {
          asyncfem::PetscRegionDistribution distribution = asyncfem::makePetscRegionDistribution(*context.mesh, totals);
          settings.solver.regionDistribution.ownedRegions = std::move(distribution.ownedRegions);
          settings.solver.regionDistribution.sum = std::move(distribution.sum);
        }
      });
  if (options.petscElements != "distributed" || scene.forceModel == asyncfem::ForceModelType::linear) return registry;
  // Each rank evaluates the nonlinear forces and tangent of its own elements; the sums reach every rank.
  const asyncfem::ProblemSettings physics = asyncfem::problemSettings(scene);
  const asyncfem::IntegratorFactory async = *registry.find("async");
  registry.add(
      "async",
      [async, physics](asyncfem::IntegratorContext context, const nlohmann::json& integratorOptions) {
        context.system.forceModel =
            asyncfem::makeRankSummedForceModel(*context.mesh, physics, std::move(context.system.forceModel));
        return async(std::move(context), integratorOptions);
      },
      registry.optionKeys("async"));
  return registry;
}

// Rank 0's summary lines of the distributed work: L's solves and rows, the regions.
void printPetscAsyncSummary(int ranks, const CommandLine& options, const asyncfem::PetscSolveCounts& totals,
                            bool linear) {
  std::printf(
      "  PETSc       %d ranks solve L's system (KSP %s): %lld solves, %lld iterations; rank 0 owns %d rows "
      "(%lld entries in other ranks' columns); region interfaces on one rank: %d, split: %d\n",
      ranks, options.petscSolver.c_str(), totals.solves, totals.iterations, totals.ownedRows, totals.offRankEntries,
      totals.regionsOnOneRank, totals.regionsSplit);
  if (options.petscRegions == "owned") {
    std::printf("  PETSc       fast regions owned by one rank each: rank 0 computes %d of %d\n", totals.regionsComputed,
                totals.regions);
  } else {
    std::printf("  PETSc       fast regions replicated: every rank computes every region\n");
  }
  std::printf("  PETSc       element loops: %s\n",
              options.petscElements == "distributed" && !linear
                  ? "each rank evaluates its elements' forces and tangent, summed over the ranks"
                  : (linear ? "K u, linear model (no element loop)" : "every rank evaluates every element"));
}

// Rank 0 opens (or continues) the output; on --resume the other ranks restore the
// checkpoint's state, reading only. Collective: every rank learns whether any failed.
std::optional<RunOutput> openOnEveryRank(asyncfem::PetscRuntime& runtime, const CommandLine& options,
                                         const asyncfem::Scene& scene, asyncfem::Simulation& simulation,
                                         RunRecord& record, std::string& failure) {
  std::optional<RunOutput> output;
  if (runtime.rank() == 0) {
    try {
      output = openOutput(options, scene, simulation, record);
    } catch (const asyncfem::Error& error) {
      failure = error.what();
    }
  } else if (options.resume) {
    try {
      RunOutput probe;
      probe.header = outputHeader(options, scene, simulation);
      probe.fingerprint =
          asyncfem::runFingerprint(fingerprintText(options.scene), scene.integrator.name, probe.header.timestep,
                                   probe.header.frameInterval, *simulation.problem);
      record.firstFrame = static_cast<int>(asyncfem::resumeFromCheckpoint(
          scene.output.file, probe.header, probe.fingerprint, simulation.timing.frameCount, *simulation.integrator,
          simulation.monitor ? &*simulation.monitor : nullptr));
    } catch (const asyncfem::Error& error) {
      failure = error.what();
    }
  }
  if (runtime.maxOverRanks(failure.empty() ? 0 : 1) != 0) {
    throw asyncfem::Error(failure.empty() ? "another rank could not open the output or resume" : failure);
  }
  return output;
}

int runPetscAsync(int argc, char** argv, const CommandLine& options, const asyncfem::Scene& scene) {
  asyncfem::Stopwatch setupWatch;
  setupWatch.start();
  asyncfem::PetscRuntime runtime(&argc, &argv, options.petscOptions);
  const bool root = runtime.rank() == 0;
  auto totals = std::make_shared<asyncfem::PetscSolveCounts>();
  asyncfem::Simulation simulation = asyncfem::buildSimulation(scene, petscAsyncRegistry(options, scene, totals));
  if (root) {
    for (const std::string& warning : simulation.warnings)
      std::cerr << "offlineSimulator: warning: " << warning << "\n";
  }
  RunRecord record;
  record.before = simulation.integrator->stats();
  record.schedule = asyncfem::CheckpointSchedule{options.checkpointEvery, options.checkpointSeconds};
  std::string failure;
  std::optional<RunOutput> output = openOnEveryRank(runtime, options, scene, simulation, record, failure);
  record.setupSeconds = setupWatch.stop();
  installStopHandlers();  // after PETSc's start, whose own handlers it replaces for these signals
  asyncfem::cli::ProgressReporter progress(
      "offlineSimulator",
      root ? asyncfem::cli::chooseProgressStyle(options.quiet, options.progress) : asyncfem::cli::ProgressStyle::none,
      simulation.timing.frameCount, record.firstFrame);
  asyncfem::Stopwatch loopWatch;
  loopWatch.start();
  int frame = record.firstFrame;
  int signal = 0;
  bool outputFailed = false;
  const auto agree = [&] {  // collective
    signal = runtime.maxOverRanks(static_cast<int>(stopSignal));
    outputFailed = runtime.maxOverRanks(failure.empty() ? 0 : 1) != 0;
    return signal == 0 && !outputFailed;
  };
  for (; frame < simulation.timing.frameCount && agree(); ++frame) {
    try {
      asyncfem::advanceFrame(simulation, frame);  // numerical failures throw alike on every rank
    } catch (const asyncfem::Error& error) {
      progress.finish();
      const int kept = output ? static_cast<int>(output->writer->numFrames()) : frame;
      throw asyncfem::Error(std::string(error.what()) + "; the " + std::to_string(kept) +
                            " frames before it are kept in " + scene.output.file.string());
    }
    if (!output) continue;
    try {
      writeFrame(*output, scene, simulation, frame, record);
    } catch (const asyncfem::Error& error) {
      failure = error.what();
    }
    progress.update(frame + 1);
  }
  if (frame == simulation.timing.frameCount) agree();
  record.loopSeconds = loopWatch.stop();
  progress.finish();
  if (outputFailed) throw asyncfem::Error(root ? failure : "rank 0 could not write the output");
  if (output) {
    if (signal != 0 && output->checkpointFrames != output->writer->numFrames()) {
      output->checkpoint(simulation, output->writer->numFrames(), scene.output.sync, record);
    }
    output->writer->close();
  }
  if (signal != 0 && frame < simulation.timing.frameCount) {
    if (root) {
      std::cerr << "offlineSimulator: interrupted by " << signalName(signal) << ": " << frame << " of "
                << simulation.timing.frameCount << " frames are complete in " << scene.output.file.string()
                << " (checkpoint after frame " << output->checkpointFrames << " in " << output->checkpointFile.string()
                << "); continue the run with:\n  mpiexec -n " << runtime.size() << " " << resumeCommand(argc, argv)
                << "\n";
    }
    return 128 + signal;
  }
  if (root && !options.quiet) {
    record.outputBytes = static_cast<std::int64_t>(fs::file_size(scene.output.file));
    printSummary(scene, simulation, record);
    printPetscAsyncSummary(runtime.size(), options, *totals, scene.forceModel == asyncfem::ForceModelType::linear);
  }
  return 0;
}
#endif

int run(int argc, char** argv) {
  CLI::App app{
      "Runs a scene file (docs/scene-format.md) and writes its frames to an .afsim file "
      "(docs/simulation-output.md)."};
  CommandLine options;
  addSceneOptions(app, options);
  addRunOptions(app, options);
  if (const std::optional<int> status = asyncfem::cli::parse(app, argc, argv, "offlineSimulator")) return *status;

  asyncfem::Stopwatch setupWatch;
  setupWatch.start();
  asyncfem::Scene scene = asyncfem::loadScene(options.scene);
  applyOverrides(options, scene);
  refuseOutputsOverInputs(options, scene);
  if (options.backend == "petsc") {
#if ASYNCFEM_OFFLINE_WITH_PETSC
    if (scene.integrator.name == "async") return runPetscAsync(argc, argv, options, scene);
    return runPetsc(argc, argv, options, scene);
#else
    throw asyncfem::Error(
        "--backend petsc: this build has no PETSc backend (install libpetsc-real-dev and openmpi-bin, e.g. with "
        "scripts/install-deps.sh, and configure again; ASYNCFEM_WITH_PETSC)");
#endif
  }
  return runLocal(argc, argv, options, scene, setupWatch);
}

}  // namespace

int main(int argc, char** argv) {
  asyncfem::preferPassiveThreadWaiting(argv);
  // Past a file size limit (ulimit -f), a write fails with EFBIG, reported like a full
  // disk, instead of SIGXFSZ ending the process.
  std::signal(SIGXFSZ, SIG_IGN);
  return asyncfem::cli::run("offlineSimulator", [&] { return run(argc, argv); });
}
