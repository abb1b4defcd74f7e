// SPDX-License-Identifier: BSD-3-Clause
#include "frameLoop.hpp"

#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <iostream>

#include "stopSignal.hpp"

namespace offline {

FrameLoopResult runFrameLoop(FrameBackend& backend, const FrameLoopRun& run) {
  asyncfem::cli::ProgressReporter progress("offlineSimulator",
                                           backend.prints() ? run.progress : asyncfem::cli::ProgressStyle::none,
                                           run.frameCount, run.firstFrame);
  asyncfem::Stopwatch loopWatch;
  asyncfem::Stopwatch storeWatch;
  loopWatch.start();
  int frame = run.firstFrame;
  try {
    for (; frame < run.frameCount && backend.agree(); ++frame) {
      backend.advance(frame);
      {
        const asyncfem::ScopedTimer timer(storeWatch);
        backend.store(frame);
      }
      progress.update(frame + 1);
    }
  } catch (const asyncfem::Error& error) {
    progress.finish();
    if (backend.outputClosed()) throw;
    // The frames before the failing one are complete, checksummed records.
    throw asyncfem::Error(std::string(error.what()) + "; the " + std::to_string(backend.framesKept(frame)) +
                          " frames before it are kept in " + run.outputFile);
  }
  if (frame == run.frameCount) backend.agree();  // a failure to store the last frame, or a late signal
  FrameLoopResult result;
  result.frames = frame;
  result.loopSeconds = loopWatch.stop();
  result.storeSeconds = storeWatch.totalSeconds();
  progress.finish();
  backend.close(frame);
  const int signal = backend.signal();
  if (signal != 0 && frame < run.frameCount) {
    if (backend.prints()) {
      std::cerr << "offlineSimulator: interrupted by " << signalName(signal) << ": " << frame << " of "
                << run.frameCount << " frames are complete in " << run.outputFile << " (checkpoint after frame "
                << backend.checkpointFrames() << " in " << run.checkpointFile << "); continue the run with:\n  "
                << backend.launcher() << run.resumeCommand << "\n";
    }
    result.exitCode = 128 + signal;
  }
  return result;
}

bool SimulationBackend::agree() {
  signal_ = stopSignal();
  return signal_ == 0;
}

std::int64_t SimulationBackend::framesKept(int /*frame*/) const { return output_.writer->numFrames(); }

void SimulationBackend::close(int /*frame*/) {
  if (signal_ != 0 && output_.checkpointFrames != output_.writer->numFrames()) {
    // The signal came after the last frame's checkpoint decision.
    output_.checkpoint(simulation_, output_.writer->numFrames(), scene_.output.sync, record_);
  }
  output_.writer->close();
}

}  // namespace offline
