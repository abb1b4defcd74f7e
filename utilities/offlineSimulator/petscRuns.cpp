// SPDX-License-Identifier: BSD-3-Clause
#include "petscRuns.hpp"

#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/integrator/registry.hpp>
#include <asyncfem/petscBackend/largeSystemSolver.hpp>
#include <asyncfem/petscBackend/petscRuntime.hpp>
#include <asyncfem/petscBackend/petscSimulation.hpp>
#include <asyncfem/petscBackend/problemSettings.hpp>
#include <asyncfem/petscBackend/rankSummedForceModel.hpp>
#include <asyncfem/runMonitor/runMonitor.hpp>
#include <asyncfem/simulationIO/checkpoint.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "frameLoop.hpp"
#include "runOutput.hpp"
#include "runSummary.hpp"
#include "stopSignal.hpp"

namespace offline {

namespace {

namespace fs = std::filesystem;

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

// What the backends of a PETSc run share: the ranks agree on a stop signal (one
// MPI_Allreduce per frame), rank 0 prints, the resume command runs under mpiexec.
class RanksBackend : public FrameBackend {
 public:
  explicit RanksBackend(const asyncfem::PetscRuntime& runtime) : runtime_(runtime) {}
  int signal() const override { return signal_; }
  bool prints() const override { return runtime_.rank() == 0; }
  std::string launcher() const override { return "mpiexec -n " + std::to_string(runtime_.size()) + " "; }

 protected:
  /// Collective: the stop signal of any rank; true when there is none.
  bool agreeOnSignal() {
    signal_ = runtime_.maxOverRanks(stopSignal());
    return signal_ == 0;
  }
  const asyncfem::PetscRuntime& runtime_;

 private:
  int signal_ = 0;
};

// The ranks of a PETSc run (PetscSimulation): every rank steps, the state is gathered to
// rank 0 (collective), which writes each frame, and checkpoints go as rank 0's schedule
// says. A stop signal that reached any rank stops every rank before the same frame (one
// MPI_Allreduce per frame), so no rank waits for the others in a collective call.
class PetscBackend final : public RanksBackend {
 public:
  PetscBackend(const asyncfem::Scene& scene, const asyncfem::PetscRuntime& runtime,
               asyncfem::PetscSimulation& simulation, PetscOutput& output)
      : RanksBackend(runtime), scene_(scene), simulation_(simulation), output_(output) {}

  bool agree() override { return agreeOnSignal(); }
  void advance(int /*frame*/) override {
    for (int s = 0; s < scene_.timing.stepsPerFrame; ++s) simulation_.step();  // non-finite states throw on every rank
  }
  void store(int frame) override {
    const bool root = prints();
    const Eigen::VectorXd u = simulation_.gatherDisplacement();
    if (output_.header.hasVelocities) {
      const Eigen::VectorXd v = simulation_.gatherVelocity();  // collective, like the gather above
      if (root) output_.writer->appendFrame(simulation_.time(), u, v);
    } else if (root) {
      output_.writer->appendFrame(simulation_.time(), u);
    }
    if (root && output_.vtuSeries && frame % output_.vtuEvery == 0) {
      output_.vtuSeries->writeFrame(frame, simulation_.time(), *output_.mesh, u);
    }
    if (output_.due(runtime_, frame + 1, scene_.timing.frameCount)) output_.checkpoint(simulation_, frame + 1);
  }
  std::int64_t framesKept(int frame) const override { return frame; }
  void close(int frame) override {
    if (frame != output_.checkpointFrames) output_.checkpoint(simulation_, frame);  // stopped by a signal
    if (prints()) output_.writer->close();
  }
  std::int64_t checkpointFrames() const override { return output_.checkpointFrames; }

 private:
  const asyncfem::Scene& scene_;
  asyncfem::PetscSimulation& simulation_;
  PetscOutput& output_;
};

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
  asyncfem::registerMultirateIntegrators(registry, [solver, totals, owned](asyncfem::AsyncSettings& settings,
                                                                           const asyncfem::IntegratorContext& context) {
    // What the backend's solvers need of the options and the partition (stable coupling,
    // structured method, regions that do not touch) is checked where every option is:
    // chooseStepSolver(), which names the refused option.
    settings.solver.processes.largeSystemSolver = asyncfem::makePetscLargeSystemSolver(*context.mesh, solver, totals);
    if (owned) {
      asyncfem::PetscRegionDistribution distribution = asyncfem::makePetscRegionDistribution(*context.mesh, totals);
      settings.solver.processes.regionDistribution.ownedRegions = std::move(distribution.ownedRegions);
      settings.solver.processes.regionDistribution.sum = std::move(distribution.sum);
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
                                         RunRecord& record) {
  std::optional<RunOutput> output;
  std::string failure;
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
      probe.fingerprint = outputFingerprint(options, scene, simulation, probe.header);
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

// The ranks of a PETSc run of the asynchronous integrator: every rank steps the replicated
// Simulation (numerical failures throw alike on every rank), rank 0 writes (the others have
// no output). The ranks agree once per frame on a stop signal and on rank 0's output
// failing, so none is left waiting in a collective call.
class PetscAsyncBackend final : public RanksBackend {
 public:
  PetscAsyncBackend(const asyncfem::Scene& scene, const asyncfem::PetscRuntime& runtime,
                    asyncfem::Simulation& simulation, std::optional<RunOutput>& output, RunRecord& record)
      : RanksBackend(runtime), scene_(scene), simulation_(simulation), output_(output), record_(record) {}

  bool agree() override {
    const bool noSignal = agreeOnSignal();
    outputFailed_ = runtime_.maxOverRanks(failure_.empty() ? 0 : 1) != 0;
    return noSignal && !outputFailed_;
  }
  void advance(int frame) override { asyncfem::advanceFrame(simulation_, frame); }
  void store(int frame) override {
    if (!output_) return;
    try {
      writeFrame(*output_, scene_, simulation_, frame, record_);
    } catch (const asyncfem::Error& error) {
      failure_ = error.what();  // every rank stops at the next agree()
    }
  }
  std::int64_t framesKept(int frame) const override { return output_ ? output_->writer->numFrames() : frame; }
  void close(int /*frame*/) override {
    if (outputFailed_) throw asyncfem::Error(prints() ? failure_ : "rank 0 could not write the output");
    if (!output_) return;
    if (signal() != 0 && output_->checkpointFrames != output_->writer->numFrames()) {
      output_->checkpoint(simulation_, output_->writer->numFrames(), scene_.output.sync, record_);
    }
    output_->writer->close();
  }
  std::int64_t checkpointFrames() const override { return output_ ? output_->checkpointFrames : 0; }

 private:
  const asyncfem::Scene& scene_;
  asyncfem::Simulation& simulation_;
  std::optional<RunOutput>& output_;
  RunRecord& record_;
  std::string failure_;  // rank 0's output failure
  bool outputFailed_ = false;
};

}  // namespace

int runPetsc(int argc, char** argv, const CommandLine& options, const asyncfem::Scene& scene) {
  asyncfem::Stopwatch setupWatch;
  setupWatch.start();
  asyncfem::PetscRuntime runtime(&argc, &argv, options.petscOptions);
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
  PetscBackend backend(scene, runtime, simulation, output);
  const FrameLoopResult result =
      runFrameLoop(backend, {firstFrame, scene.timing.frameCount,
                             asyncfem::cli::chooseProgressStyle(options.quiet, options.progress),
                             scene.output.file.string(), output.checkpointFile.string(), resumeCommand(argc, argv)});
  if (result.exitCode != 0) return result.exitCode;
  if (root && !options.quiet) printPetscSummary(scene, simulation.stats(), setupSeconds, result.loopSeconds);
  return 0;
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
  std::optional<RunOutput> output = openOnEveryRank(runtime, options, scene, simulation, record);
  record.setupSeconds = setupWatch.stop();
  installStopHandlers();  // after PETSc's start, whose own handlers it replaces for these signals
  PetscAsyncBackend backend(scene, runtime, simulation, output, record);
  const FrameLoopResult result = runFrameLoop(
      backend, {record.firstFrame, simulation.timing.frameCount,
                asyncfem::cli::chooseProgressStyle(options.quiet, options.progress), scene.output.file.string(),
                asyncfem::checkpointPathFor(scene.output.file).string(), resumeCommand(argc, argv)});
  record.loopSeconds = result.loopSeconds;
  record.outputSeconds = result.storeSeconds;
  if (result.exitCode != 0) return result.exitCode;
  if (root && !options.quiet) {
    record.outputBytes = static_cast<std::int64_t>(fs::file_size(scene.output.file));
    printSummary(scene, simulation, record);
    printPetscAsyncSummary(runtime.size(), options, *totals, scene.forceModel == asyncfem::ForceModelType::linear);
  }
  return 0;
}
}  // namespace offline
