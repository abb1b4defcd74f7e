// SPDX-License-Identifier: BSD-3-Clause
// Storage faults under offlineSimulator (docs/robustness.md, "Faults, counted"): an
// unwritable output folder, a full file system, the .afsim file deleted or truncated under
// a running job, a corrupted checkpoint then --resume. Each must end with a message naming
// the path and the cause, exit status 1, and every frame written before it readable.
//
// No test may mount anything, so a full file system is a file size limit (RLIMIT_FSIZE,
// as `ulimit -f` sets it; the simulator ignores SIGXFSZ, so writes fail with EFBIG) and
// /dev/full (every write fails with ENOSPC). Root ignores permission bits: run as root,
// the read-only cases drop CAP_DAC_OVERRIDE for the simulator with setpriv.
//
// Faults made while the run writes (the file deleted, truncated, its folder protected) are
// made at a chosen frame, not raced against a running process: the writer's test seam
// ASYNCFEM_TEST_STOP_BEFORE_FRAME=K (libraries/simulationIO, simulationWriter.cpp) stops the
// simulator before it checks and appends frame K; the test waits for the stop, changes the
// file and continues the process. Every wait has a deadline.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/simulationIO/checkpoint.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "utilityTest.hpp"

namespace {

namespace fs = std::filesystem;

const std::string simulatorPath = std::string(ASYNCFEM_BIN_DIR) + "/offlineSimulator";
const char* const setprivPath = "/usr/bin/setpriv";

using asyncfem::test::readText;

struct Finished {
  int exitCode = -1;
  std::string err;
};

struct Limits {
  std::optional<rlim_t> fileSize;   ///< RLIMIT_FSIZE in bytes
  bool withoutDacOverride = false;  ///< run as root without CAP_DAC_OVERRIDE (setpriv)
  /// The writer stops the simulator (SIGSTOP) before this frame (ASYNCFEM_TEST_STOP_BEFORE_FRAME).
  std::optional<int> stopBeforeFrame;
};

// A wait that outlasts this (seconds) is a failure, not a hang: the simulator runs a few
// frames of a 2025-vertex box, well under a second each even on a loaded machine.
constexpr double waitDeadlineSeconds = 120.0;

class StorageFaultsTest : public asyncfem::test::UtilityTest {
 protected:
  /// A box of 24 x 8 x 8 cells (2025 vertices, 48.6 kB per frame), backward Euler,
  /// 20 frames: more than any fault below is made at.
  fs::path writeScene() const {
    const fs::path path = folder_ / "scene.json";
    std::ofstream(path) << R"({
      "mesh": {"generator": "box", "size": [3, 1, 1], "cells": [24, 8, 8],
               "material": {"density": 1000, "youngsModulus": 1e5, "poissonRatio": 0.4}},
      "fixed": {"sets": ["xmin"]},
      "forces": [{"type": "pull", "set": "xmax", "force": [0, -50, 0], "window": [0, 0.1]}],
      "integrator": {"name": "backward-euler", "timestep": 0.01},
      "frames": {"rate": 20, "count": 20}
    })";
    return path;
  }

  /// Starts the simulator (stdout to /dev/null, stderr to a file); returns its pid.
  pid_t start(const std::vector<std::string>& arguments, const Limits& limits = {}) const {
    const std::string errorFile = (folder_ / "stderr.txt").string();
    const pid_t child = ::fork();
    if (child == 0) {
      const int devNull = ::open("/dev/null", O_RDWR);
      const int error = ::open(errorFile.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(devNull, STDIN_FILENO);
      ::dup2(devNull, STDOUT_FILENO);
      ::dup2(error, STDERR_FILENO);
      if (limits.stopBeforeFrame) {
        ::setenv("ASYNCFEM_TEST_STOP_BEFORE_FRAME", std::to_string(*limits.stopBeforeFrame).c_str(), 1);
      }
      if (limits.fileSize) {
        const rlimit limit{*limits.fileSize, *limits.fileSize};
        ::setrlimit(RLIMIT_FSIZE, &limit);
      }
      std::vector<std::string> command;
      if (limits.withoutDacOverride && ::geteuid() == 0) {
        command = {setprivPath, "--bounding-set", "-dac_override,-dac_read_search", "--"};
      }
      command.push_back(simulatorPath);
      command.insert(command.end(), arguments.begin(), arguments.end());
      asyncfem::test::execCommand(std::move(command));
    }
    return child;
  }

  /// Waits for the child (killing it after `seconds`); its exit status and stderr.
  Finished finish(pid_t child, double seconds = waitDeadlineSeconds) const {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    int status = 0;
    while (::waitpid(child, &status, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > deadline) {
        ::kill(child, SIGKILL);
        ::waitpid(child, &status, 0);
        ADD_FAILURE() << "offlineSimulator did not stop within " << seconds << " s";
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, readText(folder_ / "stderr.txt")};
  }

  Finished run(const std::vector<std::string>& arguments, const Limits& limits = {}) const {
    return finish(start(arguments, limits));
  }

  /// Waits until the child stops itself (Limits::stopBeforeFrame); false, with the child
  /// reaped, if it ended first or did not stop within the deadline.
  static bool waitForStop(pid_t child) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(waitDeadlineSeconds);
    int status = 0;
    for (;;) {
      const pid_t changed = ::waitpid(child, &status, WNOHANG | WUNTRACED);
      if (changed == child && WIFSTOPPED(status)) return true;
      if (changed == child || changed < 0) return false;
      if (std::chrono::steady_clock::now() > deadline) {
        ::kill(child, SIGKILL);
        ::waitpid(child, &status, 0);
        ADD_FAILURE() << "offlineSimulator did not stop before its frame within " << waitDeadlineSeconds << " s";
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }

  /// Starts the simulator to stop before `frame`, waits for the stop; returns its pid, or
  /// -1 if it did not stop there.
  pid_t startStoppedBefore(int frame, const std::vector<std::string>& arguments, Limits limits = {}) const {
    limits.stopBeforeFrame = frame;
    const pid_t child = start(arguments, limits);
    return waitForStop(child) ? child : -1;
  }

  /// Every complete frame of the file passes its checks; returns how many there are.
  static std::int64_t readableFrames(const fs::path& output) {
    asyncfem::SimulationReader reader(output);
    reader.verifyAll();
    return reader.numFrames();
  }

  /// Root ignores permission bits: the read-only cases need setpriv to drop the override.
  static bool canTestPermissions() { return ::geteuid() != 0 || fs::exists(setprivPath); }
};

int numberAfter(const std::string& text, const std::string& pattern) {
  std::smatch match;
  if (!std::regex_search(text, match, std::regex(pattern + "([0-9]+)"))) return -1;
  return std::stoi(match[1].str());
}

TEST_F(StorageFaultsTest, ReadOnlyOutputFolderIsNamedWithTheCause) {
  if (!canTestPermissions()) GTEST_SKIP() << "running as root without setpriv: permission bits do not apply";
  const fs::path scene = writeScene();
  const fs::path readOnly = folder_ / "readOnly";
  fs::create_directories(readOnly);
  fs::permissions(readOnly, fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                                fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec);
  const Limits withoutOverride{std::nullopt, true};

  const fs::path output = readOnly / "run.afsim";
  const Finished file = run({scene.string(), "--quiet", "--frames", "3", "--output", output.string()}, withoutOverride);
  EXPECT_EQ(file.exitCode, 1) << file.err;
  EXPECT_NE(file.err.find("offlineSimulator: " + output.string() + ": cannot create: Permission denied"),
            std::string::npos)
      << file.err;
  EXPECT_FALSE(fs::exists(output));

  const fs::path nested = readOnly / "frames" / "run.afsim";
  const Finished folder =
      run({scene.string(), "--quiet", "--frames", "3", "--output", nested.string()}, withoutOverride);
  EXPECT_EQ(folder.exitCode, 1) << folder.err;
  EXPECT_NE(folder.err.find("offlineSimulator: " + nested.parent_path().string() +
                            ": cannot create the output folder: Permission denied"),
            std::string::npos)
      << folder.err;
  fs::permissions(readOnly, fs::perms::owner_all);
}

// The folder turns read-only while the run writes: the .afsim file is open and keeps
// growing, but the next checkpoint (written to a temporary file and renamed) cannot be
// created. The run stops there with every frame readable, and it can be resumed.
TEST_F(StorageFaultsTest, FolderTurningReadOnlyStopsAtTheNextCheckpoint) {
  if (!canTestPermissions()) GTEST_SKIP() << "running as root without setpriv: permission bits do not apply";
  const fs::path scene = writeScene();
  const fs::path output = folder_ / "out" / "run.afsim";
  // Protected before frame 2 is appended: frame 2 still goes to the open file, its
  // checkpoint's temporary file cannot be created.
  const pid_t child =
      startStoppedBefore(2, {scene.string(), "--quiet", "--checkpoint-every", "1", "--output", output.string()},
                         Limits{std::nullopt, true});
  ASSERT_GT(child, 0) << readText(folder_ / "stderr.txt");
  fs::permissions(output.parent_path(), fs::perms::owner_read | fs::perms::owner_exec);
  ::kill(child, SIGCONT);
  const Finished finished = finish(child);
  fs::permissions(output.parent_path(), fs::perms::owner_all);
  EXPECT_EQ(finished.exitCode, 1) << finished.err;
  const fs::path checkpoint = asyncfem::checkpointPathFor(output);
  const fs::path temporary = checkpoint.string() + ".tmp";
  EXPECT_NE(finished.err.find(temporary.string() + ": cannot create: Permission denied"), std::string::npos)
      << finished.err;
  const std::int64_t frames = readableFrames(output);
  EXPECT_EQ(frames, 3);
  EXPECT_NE(finished.err.find("the " + std::to_string(frames) + " frames before it are kept in " + output.string()),
            std::string::npos)
      << finished.err;
  // The last checkpoint is the frame before; resuming continues from it.
  const Finished resumed =
      run({scene.string(), "--quiet", "--resume", "--frames", std::to_string(frames + 2), "--output", output.string()});
  EXPECT_EQ(resumed.exitCode, 0) << resumed.err;
  EXPECT_EQ(readableFrames(output), frames + 2);
}

// RLIMIT_FSIZE at 200 KiB: the header and 4 frames of 48.6 kB fit, the 5th does not. The
// partial record is cut off again.
TEST_F(StorageFaultsTest, FileSizeLimitStopsWithEveryFrameBeforeItReadable) {
  const fs::path scene = writeScene();
  const fs::path output = folder_ / "out" / "run.afsim";
  const Finished finished = run({scene.string(), "--quiet", "--frames", "20", "--output", output.string()},
                                Limits{rlim_t{200 * 1024}, false});
  EXPECT_EQ(finished.exitCode, 1) << finished.err;
  EXPECT_NE(finished.err.find("offlineSimulator: " + output.string() +
                              ": frame 4: write failed: File too large; the file keeps its 4 complete frames"),
            std::string::npos)
      << finished.err;
  asyncfem::SimulationReader reader(output);
  EXPECT_EQ(reader.numFrames(), 4);
  EXPECT_EQ(reader.truncatedTrailingBytes(), 0);
  reader.verifyAll();
  EXPECT_FALSE(fs::exists(asyncfem::checkpointPathFor(output).string() + ".tmp"));
}

// At 90 KiB the first checkpoint (97 kB, written before the first frame) does not fit:
// its temporary file goes again and the message names it.
TEST_F(StorageFaultsTest, FileSizeLimitOnTheCheckpointNamesIt) {
  const fs::path scene = writeScene();
  const fs::path output = folder_ / "out" / "run.afsim";
  const Finished finished =
      run({scene.string(), "--quiet", "--frames", "20", "--output", output.string()}, Limits{rlim_t{90 * 1024}, false});
  EXPECT_EQ(finished.exitCode, 1) << finished.err;
  const std::string checkpoint = asyncfem::checkpointPathFor(output).string();
  EXPECT_NE(finished.err.find(checkpoint + ".tmp: write failed: File too large; the previous checkpoint " + checkpoint +
                              " is unchanged"),
            std::string::npos)
      << finished.err;
  EXPECT_FALSE(fs::exists(checkpoint + ".tmp"));
  EXPECT_EQ(readableFrames(output), 0);
}

// /dev/full: every write fails with ENOSPC, the message says so.
TEST_F(StorageFaultsTest, FullDeviceSaysNoSpace) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const Finished finished = run({writeScene().string(), "--quiet", "--frames", "3", "--output", "/dev/full"});
  EXPECT_EQ(finished.exitCode, 1) << finished.err;
  EXPECT_NE(finished.err.find("offlineSimulator: /dev/full: cannot write the header: No space left on device"),
            std::string::npos)
      << finished.err;
}

// Deleted under the run: the writer notices before the next frame, writes the complete
// frames back to the path, and stops; the run can be resumed from there.
TEST_F(StorageFaultsTest, DeletedOutputIsWrittenBackAndTheRunStops) {
  const fs::path scene = writeScene();
  const fs::path output = folder_ / "out" / "run.afsim";
  // Deleted with frames 0 and 1 written: the writer notices before frame 2.
  const pid_t child = startStoppedBefore(2, {scene.string(), "--quiet", "--output", output.string()});
  ASSERT_GT(child, 0) << readText(folder_ / "stderr.txt");
  fs::remove(output);
  ::kill(child, SIGCONT);
  const Finished finished = finish(child);
  EXPECT_EQ(finished.exitCode, 1) << finished.err;
  const int frames = numberAfter(finished.err, output.string() + ": frame ");
  ASSERT_EQ(frames, 2) << finished.err;
  EXPECT_NE(finished.err.find(": the file was deleted while the run was writing it; its " + std::to_string(frames) +
                              " complete frames are written back to " + output.string()),
            std::string::npos)
      << finished.err;
  EXPECT_EQ(readableFrames(output), frames);
  const Finished resumed =
      run({scene.string(), "--quiet", "--resume", "--frames", std::to_string(frames + 1), "--output", output.string()});
  EXPECT_EQ(resumed.exitCode, 0) << resumed.err;
  EXPECT_EQ(readableFrames(output), frames + 1);
}

// Truncated under the run to its header, one frame and 100 bytes of the next: the writer
// stops before appending after the cut (which would leave a hole) and says what is left.
TEST_F(StorageFaultsTest, TruncatedOutputStopsTheRunAndKeepsWhatIsLeft) {
  const fs::path scene = writeScene();
  const fs::path output = folder_ / "out" / "run.afsim";
  // Cut with frames 0 to 2 written: the writer notices before frame 3.
  const pid_t child = startStoppedBefore(3, {scene.string(), "--quiet", "--output", output.string()});
  ASSERT_GT(child, 0) << readText(folder_ / "stderr.txt");
  std::int64_t cut = 0;
  {
    const asyncfem::SimulationReader reader(output);
    cut = reader.header().headerBytes() + reader.header().recordBytes() + 100;
  }
  fs::resize_file(output, static_cast<std::uintmax_t>(cut));
  ::kill(child, SIGCONT);
  const Finished finished = finish(child);
  EXPECT_EQ(finished.exitCode, 1) << finished.err;
  const int frames = numberAfter(finished.err, output.string() + ": frame ");
  EXPECT_EQ(frames, 3) << finished.err;
  EXPECT_NE(finished.err.find("something else truncated it while the run was writing it; it keeps 1 complete frame "
                              "of " +
                              std::to_string(frames)),
            std::string::npos)
      << finished.err;
  asyncfem::SimulationReader reader(output);
  EXPECT_EQ(reader.numFrames(), 1);
  EXPECT_EQ(reader.truncatedTrailingBytes(), 100);
  reader.verifyAll();
}

// A checkpoint damaged on disk (a flipped byte, cut short, emptied): --resume refuses with
// the checkpoint's path and what is wrong, and leaves the output byte for byte as it was.
TEST_F(StorageFaultsTest, CorruptedCheckpointRefusesToResumeAndLeavesTheOutput) {
  const fs::path scene = writeScene();
  const fs::path output = folder_ / "out" / "run.afsim";
  ASSERT_EQ(run({scene.string(), "--quiet", "--frames", "4", "--output", output.string()}).exitCode, 0);
  const std::string frames = readText(output);
  const fs::path checkpoint = asyncfem::checkpointPathFor(output);
  const std::string intact = readText(checkpoint);
  std::string flipped = intact;
  flipped[flipped.size() / 2] = static_cast<char>(flipped[flipped.size() / 2] ^ 4);
  const std::vector<std::pair<std::string, std::string>> damages{
      {flipped, "checkpoint checksum mismatch: the file is corrupted"},
      {intact.substr(0, 100), "checkpoint is 100 bytes, its header implies " + std::to_string(intact.size()) +
                                  ": the file is truncated or corrupted"},
      {"", "truncated checkpoint: 0 bytes, expected at least 64"}};
  for (const auto& [bytes, cause] : damages) {
    SCOPED_TRACE(cause);
    std::ofstream(checkpoint, std::ios::binary | std::ios::trunc) << bytes;
    const Finished resumed = run({scene.string(), "--quiet", "--resume", "--frames", "8", "--output", output.string()});
    EXPECT_EQ(resumed.exitCode, 1) << resumed.err;
    EXPECT_NE(resumed.err.find("offlineSimulator: cannot resume: " + checkpoint.string() + ": " + cause + "; " +
                               output.string() + " is left as it is; run without --resume to start over"),
              std::string::npos)
        << resumed.err;
    EXPECT_TRUE(readText(output) == frames);
    EXPECT_EQ(readableFrames(output), 4);
  }
}

}  // namespace
