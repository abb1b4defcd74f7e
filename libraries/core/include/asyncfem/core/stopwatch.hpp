// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <chrono>

namespace asyncfem {

/// Wall-clock stopwatch that accumulates seconds over several start/stop intervals.
class Stopwatch {
 public:
  using Clock = std::chrono::steady_clock;

  void start() { startTime_ = Clock::now(); }
  /// Stops the running interval and returns its length in seconds.
  double stop() {
    const double s = std::chrono::duration<double>(Clock::now() - startTime_).count();
    total_ += s;
    return s;
  }
  double totalSeconds() const { return total_; }
  void reset() { total_ = 0.0; }

 private:
  Clock::time_point startTime_ = Clock::now();
  double total_ = 0.0;
};

/// Adds the lifetime of the guard to a Stopwatch (RAII timing of a scope).
class ScopedTimer {
 public:
  explicit ScopedTimer(Stopwatch& watch) : watch_(watch) { watch_.start(); }
  ~ScopedTimer() { watch_.stop(); }
  ScopedTimer(const ScopedTimer&) = delete;
  ScopedTimer& operator=(const ScopedTimer&) = delete;

 private:
  Stopwatch& watch_;
};

}  // namespace asyncfem
