// SPDX-License-Identifier: BSD-3-Clause
#include "progress.hpp"

#include <unistd.h>

#include <cmath>
#include <utility>

namespace asyncfem::cli {

ProgressStyle chooseProgressStyle(bool quiet, bool forceBar) {
  if (quiet) {
    return ProgressStyle::none;
  }
  return forceBar || ::isatty(STDERR_FILENO) != 0 ? ProgressStyle::bar : ProgressStyle::lines;
}

std::string formatDuration(double seconds) {
  char text[32];
  if (seconds < 60.0) {
    std::snprintf(text, sizeof(text), "%.1f s", seconds);
  } else if (seconds < 3600.0) {
    const int whole = static_cast<int>(seconds);
    std::snprintf(text, sizeof(text), "%d:%02d", whole / 60, whole % 60);
  } else {
    const int whole = static_cast<int>(seconds);
    std::snprintf(text, sizeof(text), "%d:%02d:%02d", whole / 3600, (whole / 60) % 60, whole % 60);
  }
  return text;
}

ProgressReporter::ProgressReporter(std::string program, ProgressStyle style, int totalFrames, int firstFrame,
                                   std::FILE* out)
    : program_(std::move(program)),
      style_(style),
      totalFrames_(totalFrames > 0 ? totalFrames : 1),
      firstFrame_(firstFrame),
      out_(out),
      latest_(firstFrame) {
  lastPercentPrinted_ = static_cast<int>(std::floor(100.0 * firstFrame_ / totalFrames_));
}

void ProgressReporter::update(int framesDone) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (style_ == ProgressStyle::none || framesDone < latest_) {
    return;
  }
  latest_ = framesDone;
  const Clock::time_point now = Clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const int framesThisRun = framesDone - firstFrame_;
  const double remaining = framesThisRun > 0 ? elapsed * (totalFrames_ - framesDone) / framesThisRun : 0.0;
  if (style_ == ProgressStyle::bar) {
    drawBar(framesDone, now, elapsed, remaining);
  } else {
    printLine(framesDone, now, elapsed, remaining);
  }
}

void ProgressReporter::drawBar(int framesDone, Clock::time_point now, double elapsed, double remaining) {
  // Redraw at most ~20 times a second, and always for the last frame.
  if (framesDone < totalFrames_ && barDrawn_ && now - lastPrint_ < std::chrono::milliseconds(50)) {
    return;
  }
  const double fraction = static_cast<double>(framesDone) / totalFrames_;
  const int percent = static_cast<int>(std::floor(100.0 * fraction));
  constexpr int width = 30;
  const int filled = static_cast<int>(std::round(fraction * width));
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.append(static_cast<std::size_t>(width - filled), '.');
  std::fprintf(out_, "\r[%s] %d/%d frames %3d%%  elapsed %s  ETA %s   ", bar.c_str(), framesDone, totalFrames_, percent,
               formatDuration(elapsed).c_str(), formatDuration(remaining).c_str());
  std::fflush(out_);
  barDrawn_ = true;
  lastPrint_ = now;
}

void ProgressReporter::printLine(int framesDone, Clock::time_point now, double elapsed, double remaining) {
  const double fraction = static_cast<double>(framesDone) / totalFrames_;
  const int percent = static_cast<int>(std::floor(100.0 * fraction));
  // Every 10% of the frames or every 10 s, whichever comes first.
  const bool step = percent / 10 > lastPercentPrinted_ / 10;
  const bool late = now - lastPrint_ >= std::chrono::seconds(10);
  if (!step && !late && framesDone < totalFrames_) {
    return;
  }
  if (framesDone == totalFrames_ && lastPercentPrinted_ == 100) {
    return;
  }
  std::fprintf(out_, "%s: frame %d/%d (%d%%), elapsed %s, ETA %s\n", program_.c_str(), framesDone, totalFrames_,
               percent, formatDuration(elapsed).c_str(), formatDuration(remaining).c_str());
  std::fflush(out_);
  lastPercentPrinted_ = percent;
  lastPrint_ = now;
}

void ProgressReporter::finish() {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (style_ == ProgressStyle::bar && barDrawn_) {
    std::fputc('\n', out_);
    std::fflush(out_);
    barDrawn_ = false;
  }
}

}  // namespace asyncfem::cli
