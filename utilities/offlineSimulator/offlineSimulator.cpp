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
//
// This file holds the command line and the local run; the frames of every backend go
// through the one loop of frameLoop.hpp (a run on this process, or the ranks of a PETSc
// run: petscRuns.cpp), into the output of runOutput.hpp, reported by runSummary.hpp.
#include <CLI/CLI.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/runMonitor/runMonitor.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/sceneIO/stepGrowthCheck.hpp>
#include <asyncfem/sceneIO/vegaConfig.hpp>
#include <asyncfem/simulationIO/checkpoint.hpp>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "commandLine.hpp"
#include "commandLineOptions.hpp"
#include "frameLoop.hpp"
#include "progress.hpp"
#include "runOutput.hpp"
#include "runSummary.hpp"
#include "stopSignal.hpp"
#if ASYNCFEM_OFFLINE_WITH_PETSC
#include "petscRuns.hpp"
#endif

namespace offline {
namespace {

namespace fs = std::filesystem;

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
  SimulationBackend backend(scene, simulation, output, record);
  const FrameLoopResult result =
      runFrameLoop(backend, {record.firstFrame, simulation.timing.frameCount,
                             asyncfem::cli::chooseProgressStyle(options.quiet, options.progress),
                             scene.output.file.string(), output.checkpointFile.string(), resumeCommand(argc, argv)});
  record.loopSeconds = result.loopSeconds;
  record.outputSeconds = result.storeSeconds;
  if (result.exitCode != 0) return result.exitCode;
  if (!options.quiet) {
    record.outputBytes = static_cast<std::int64_t>(fs::file_size(scene.output.file));
    printSummary(scene, simulation, record);
  }
  return 0;
}

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
}  // namespace offline

int main(int argc, char** argv) {
  asyncfem::preferPassiveThreadWaiting(argv);
  // Past a file size limit (ulimit -f), a write fails with EFBIG, reported like a full
  // disk, instead of SIGXFSZ ending the process.
  std::signal(SIGXFSZ, SIG_IGN);
  return asyncfem::cli::run("offlineSimulator", [&] { return offline::run(argc, argv); });
}
