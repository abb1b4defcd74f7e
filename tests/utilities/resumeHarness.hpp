// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What the resume tests share (resumeMatrixTest.cpp, resumeMatrixPetscTest.cpp): running a
// command in the background with its output in files, stopping it at a frame, waiting with
// a deadline, and comparing the frames of two simulation files.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/simulationIO/checkpoint.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "utilityTest.hpp"

namespace asyncfem::test {

/// The seed of the interruption frames: ASYNCFEM_RESUME_MATRIX_SEED, or a fixed default.
inline std::uint64_t matrixSeed() {
  const char* text = std::getenv("ASYNCFEM_RESUME_MATRIX_SEED");
  return text != nullptr ? std::strtoull(text, nullptr, 10) : 20261202ULL;
}

/// FNV-1a: a hash that is the same in every build, so a case's frame is reproducible.
inline std::uint64_t stableHash(const std::string& text) {
  std::uint64_t hash = 14695981039346656037ULL;
  for (const char c : text) hash = (hash ^ static_cast<unsigned char>(c)) * 1099511628211ULL;
  return hash;
}

/// A process started by ResumeHarness::startCommand.
struct Child {
  pid_t pid = -1;
  int status = 0;
  bool done = false;
};

/// A scratch-folder fixture that runs commands in the background.
class ResumeHarness : public UtilityTest {
 protected:
  /// Starts command (command[0] an absolute path) with one OpenMP thread (multi-threaded
  /// reductions are not bit-reproducible run to run), stdin from /dev/null, stdout and
  /// stderr to files named by `tag` in the folder.
  Child startCommand(const std::vector<std::string>& command, const std::string& tag) const {
    const std::string out = (folder_ / (tag + ".out")).string();
    const std::string err = (folder_ / (tag + ".err")).string();
    Child child;
    child.pid = ::fork();
    if (child.pid == 0) {
      const int devNull = ::open("/dev/null", O_RDONLY);
      const int outFd = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int errFd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(devNull, STDIN_FILENO);
      ::dup2(outFd, STDOUT_FILENO);
      ::dup2(errFd, STDERR_FILENO);
      ::setenv("OMP_NUM_THREADS", "1", 1);
      execCommand(command);
    }
    return child;
  }

  /// Non-blocking: has the child ended?
  static bool ended(Child& child) {
    if (!child.done && ::waitpid(child.pid, &child.status, WNOHANG) == child.pid) child.done = true;
    return child.done;
  }

  /// Waits for the child, killing it after `seconds` (a test never hangs).
  static void finish(Child& child, double seconds) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (!ended(child)) {
      if (std::chrono::steady_clock::now() > deadline) {
        ::kill(child.pid, SIGKILL);
        ::waitpid(child.pid, &child.status, 0);
        child.done = true;
        ADD_FAILURE() << "the command did not end within " << seconds << " s";
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }

  /// Runs command to its end (at most 120 s); its exit status (-1 if it did not exit normally).
  int runCommandToEnd(const std::vector<std::string>& command, const std::string& tag) const {
    Child child = startCommand(command, tag);
    finish(child, 120.0);
    return WIFEXITED(child.status) ? WEXITSTATUS(child.status) : -1;
  }

  std::string printed(const std::string& tag, const char* stream) const {
    return readText(folder_ / (tag + "." + stream));
  }

  /// Polls the output until it holds `frames` complete frames; false if the run ended
  /// first or 60 s passed.
  static bool waitForFrames(const std::filesystem::path& file, std::int64_t frames, Child& child) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (std::chrono::steady_clock::now() < deadline && !ended(child)) {
      std::error_code ignored;
      if (std::filesystem::exists(file, ignored)) {
        try {
          if (SimulationReader(file).numFrames() >= frames) return true;
        } catch (const Error&) {
          // the header is not complete yet
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
  }
};

/// What a stopped run left: its complete frames in the output and in the checkpoint.
struct LeftBehind {
  std::int64_t onDisk = 0;
  std::int64_t checkpointed = 0;
};

/// Reads what the run stopped once frame stopAfter was on disk left in output, and checks
/// it: at least stopAfter frames, and after SIGINT (not after kill -9) a checkpoint of
/// every one of them.
inline LeftBehind checkLeftBehind(const std::filesystem::path& output, std::int64_t stopAfter, bool kill9) {
  LeftBehind left;
  left.onDisk = SimulationReader(output).numFrames();
  left.checkpointed = readCheckpoint(checkpointPathFor(output)).frames;
  EXPECT_GE(left.onDisk, stopAfter);
  if (!kill9) {
    EXPECT_EQ(left.checkpointed, left.onDisk) << "SIGINT must checkpoint the last finished frame";
  }
  return left;
}

/// The largest difference between the frames of two files, and the largest values.
struct Difference {
  double displacement = 0.0;
  double velocity = 0.0;
  double largestDisplacement = 0.0;
  double largestVelocity = 0.0;
  bool sameTimes = true;
};

/// Frames 0..frames-1 of a against those of b (b's values give the largest ones).
inline Difference compareFrames(const std::filesystem::path& a, const std::filesystem::path& b, std::int64_t frames) {
  SimulationReader ra(a), rb(b);
  Difference d;
  for (std::int64_t k = 0; k < frames; ++k) {
    const SimulationFrame fa = ra.readFrame(k), fb = rb.readFrame(k);
    d.sameTimes = d.sameTimes && fa.time == fb.time;
    d.displacement = std::max(d.displacement, (fa.displacement - fb.displacement).cwiseAbs().maxCoeff());
    d.velocity = std::max(d.velocity, (fa.velocity - fb.velocity).cwiseAbs().maxCoeff());
    d.largestDisplacement = std::max(d.largestDisplacement, fb.displacement.cwiseAbs().maxCoeff());
    d.largestVelocity = std::max(d.largestVelocity, fb.velocity.cwiseAbs().maxCoeff());
  }
  return d;
}

}  // namespace asyncfem::test
