// SPDX-License-Identifier: BSD-3-Clause
// Progress reporting of the offline simulator on stderr.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

namespace asyncfem::offline {

/// How progress is shown.
enum class ProgressStyle {
  none,   ///< --quiet
  bar,    ///< a bar redrawn in place with '\r' (stderr is a terminal, or --progress)
  lines,  ///< one plain line every 10% or 10 s, for logs (stderr is a file or pipe)
};

/// Reports "frame k of n" with elapsed time and an estimate of the time left.
class ProgressReporter {
 public:
  /// firstFrame: frames already done when the run starts (a resumed run); the time left
  /// is estimated from the frames done since.
  ProgressReporter(ProgressStyle style, int totalFrames, int firstFrame = 0, std::FILE* out = stderr);
  /// Call after each finished frame (framesDone = firstFrame + 1 .. totalFrames).
  void update(int framesDone);
  /// Ends the bar's line (call once, also on errors, before printing anything else).
  void finish();

 private:
  using Clock = std::chrono::steady_clock;
  static std::string formatSeconds(double seconds);

  ProgressStyle style_;
  int totalFrames_;
  int firstFrame_;
  std::FILE* out_;
  Clock::time_point start_ = Clock::now();
  Clock::time_point lastPrint_ = Clock::now();
  int lastPercentPrinted_ = 0;
  bool barDrawn_ = false;
};

}  // namespace asyncfem::offline
