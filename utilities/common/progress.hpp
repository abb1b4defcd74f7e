// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Progress of a utility's frame loop on stderr, shared by offlineSimulator and frameRenderer.

#include <chrono>
#include <cstdio>
#include <mutex>
#include <string>

namespace asyncfem::cli {

/// How progress is shown.
enum class ProgressStyle {
  none,   ///< --quiet
  bar,    ///< a bar redrawn in place with '\r' (stderr is a terminal, or --progress)
  lines,  ///< "PROGRAM: frame k/n (p%), elapsed .., ETA .." every 10% or 10 s, for logs
};

/// The style of the usual options: none with --quiet, a bar with --progress or when stderr
/// is a terminal, plain lines otherwise.
ProgressStyle chooseProgressStyle(bool quiet, bool forceBar);

/// "12.3 s" under a minute, "m:ss" under an hour, "h:mm:ss" beyond.
std::string formatDuration(double seconds);

/// Reports "frame k of n" with the elapsed time and an estimate of the time left. update()
/// may be called from several threads; a count lower than one already reported is ignored.
class ProgressReporter {
 public:
  /// program prefixes the plain lines. firstFrame: frames already done when the run starts
  /// (a resumed run); the time left is estimated from the frames done since.
  ProgressReporter(std::string program, ProgressStyle style, int totalFrames, int firstFrame = 0,
                   std::FILE* out = stderr);
  /// Call after each finished frame (framesDone = firstFrame + 1 .. totalFrames).
  void update(int framesDone);
  /// Ends the bar's line (call once, also on errors, before printing anything else).
  void finish();

 private:
  using Clock = std::chrono::steady_clock;

  /// The two styles' output for framesDone frames at time now (mutex_ held).
  void drawBar(int framesDone, Clock::time_point now, double elapsed, double remaining);
  void printLine(int framesDone, Clock::time_point now, double elapsed, double remaining);

  std::string program_;
  ProgressStyle style_;
  int totalFrames_;
  int firstFrame_;
  std::FILE* out_;
  std::mutex mutex_;
  Clock::time_point start_ = Clock::now();
  Clock::time_point lastPrint_ = Clock::now();
  int latest_ = 0;
  int lastPercentPrinted_ = 0;
  bool barDrawn_ = false;
};

}  // namespace asyncfem::cli
