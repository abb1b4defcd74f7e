// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// offlineSimulator's one frame loop, whatever the backend: frames are stepped, stored and
// checkpointed, a stop signal ends the run after a whole frame, a failing frame's error
// names the frames kept. What differs between a local run and the ranks of a PETSc run
// (which process writes, how the processes agree on stopping) is a FrameBackend.

#include <cstdint>
#include <string>

#include "progress.hpp"
#include "runOutput.hpp"
#include "runSummary.hpp"

namespace offline {

/// Where a run's frames are computed and stored: this process (SimulationBackend), or the
/// ranks of a PETSc run, of which rank 0 writes (petscRuns.cpp). runFrameLoop() calls, per
/// frame, agree(), advance() and store(); after the last one agree() once more and close().
class FrameBackend {
 public:
  virtual ~FrameBackend() = default;
  /// Collective: whether the run goes on (no stop signal on any process, the output
  /// intact), remembering the signal for signal().
  virtual bool agree() = 0;
  /// The stop signal the last agree() saw (0: none).
  virtual int signal() const = 0;
  /// Steps frame `frame`: numerical failures throw asyncfem::Error, alike on every process.
  virtual void advance(int frame) = 0;
  /// Stores frame `frame`: its record, the checkpoint when due, its .vtu file.
  virtual void store(int frame) = 0;
  /// The frames complete in the output when frame `frame` failed (for the error message).
  virtual std::int64_t framesKept(int frame) const = 0;
  /// Whether a failure closed the output: a storage fault, whose message says what the file holds.
  virtual bool outputClosed() const { return false; }
  /// Collective, after the loop stopped at `frame`: the checkpoint of a run stopped by a
  /// signal, the output closed.
  virtual void close(int frame) = 0;
  /// The frames the last checkpoint holds.
  virtual std::int64_t checkpointFrames() const = 0;
  /// Whether this process draws the progress and prints messages (rank 0).
  virtual bool prints() const { return true; }
  /// What the resume command runs under ("mpiexec -n 2 "; empty for one process).
  virtual std::string launcher() const { return ""; }
};

/// What runFrameLoop() is told about the run.
struct FrameLoopRun {
  int firstFrame = 0;  ///< frames already in the output (a resumed run)
  int frameCount = 0;
  asyncfem::cli::ProgressStyle progress = asyncfem::cli::ProgressStyle::none;
  std::string outputFile;      ///< for messages
  std::string checkpointFile;  ///< for messages
  std::string resumeCommand;   ///< this command with --resume (stopSignal.hpp)
};

/// What the loop did.
struct FrameLoopResult {
  int exitCode = 0;  ///< 0: every frame done; 128 + signal: stopped by it (the message is printed)
  int frames = 0;    ///< frames complete
  double loopSeconds = 0.0;
  double storeSeconds = 0.0;  ///< of which store()
};

/// Runs frames run.firstFrame .. run.frameCount - 1 with backend, drawing the progress,
/// until the last one or until agree() says stop; then closes the output. A stopped run
/// prints "offlineSimulator: interrupted by SIGNAL: ..." with the command that continues
/// it. An asyncfem::Error from a frame is thrown again with the frames kept in the output
/// (as is when the output was closed by it).
FrameLoopResult runFrameLoop(FrameBackend& backend, const FrameLoopRun& run);

/// The backend of a run on this process: advanceFrame() under the run monitor, writeFrame().
class SimulationBackend : public FrameBackend {
 public:
  SimulationBackend(const asyncfem::Scene& scene, asyncfem::Simulation& simulation, RunOutput& output,
                    RunRecord& record)
      : scene_(scene), simulation_(simulation), output_(output), record_(record) {}

  bool agree() override;
  int signal() const override { return signal_; }
  void advance(int frame) override { asyncfem::advanceFrame(simulation_, frame); }
  void store(int frame) override { writeFrame(output_, scene_, simulation_, frame, record_); }
  std::int64_t framesKept(int frame) const override;
  bool outputClosed() const override { return !output_.writer->isOpen(); }
  void close(int frame) override;
  std::int64_t checkpointFrames() const override { return output_.checkpointFrames; }

 protected:
  const asyncfem::Scene& scene_;
  asyncfem::Simulation& simulation_;
  RunOutput& output_;
  RunRecord& record_;
  int signal_ = 0;
};

}  // namespace offline
