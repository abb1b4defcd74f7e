// SPDX-License-Identifier: BSD-3-Clause
// offlineSimulator end to end: runs the built executable on scenes written by the tests
// and checks its exit status, messages and the .afsim file it leaves.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/simulationIO/checkpoint.hpp>
#include <asyncfem/simulationIO/crc32.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <cctype>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "utilityTest.hpp"

namespace {

namespace fs = std::filesystem;

const std::string simulatorPath = std::string(ASYNCFEM_BIN_DIR) + "/offlineSimulator";

using asyncfem::test::readText;
using asyncfem::test::RunResult;

class OfflineSimulatorTest : public asyncfem::test::UtilityTest {
 protected:
  /// A box of 3 x 1 x 1 cells fixed at x = 0, pulled at x = 3 for 0.1 s, backward Euler
  /// with 5 steps per frame, output "out/run.afsim" next to the scene.
  static nlohmann::json smallScene() {
    return nlohmann::json::parse(R"({
      "mesh": {"generator": "box", "size": [3, 1, 1], "cells": [3, 1, 1],
               "material": {"density": 1000, "youngsModulus": 1e5, "poissonRatio": 0.4}},
      "fixed": {"sets": ["xmin"]},
      "forces": [{"type": "pull", "set": "xmax", "force": [0, -50, 0], "window": [0, 0.1]}],
      "integrator": {"name": "backward-euler", "timestep": 0.01},
      "frames": {"rate": 20, "count": 6},
      "output": {"file": "out/run.afsim"}
    })");
  }

  fs::path writeScene(const nlohmann::json& scene, const std::string& name = "scene.json") const {
    const fs::path path = folder_ / name;
    std::ofstream(path) << scene.dump(2);
    return path;
  }

  /// Runs the simulator with the shell-quoted arguments; stdout and stderr separately
  /// (both are files, so stderr is not a terminal).
  RunResult run(const std::string& arguments) const { return runCommand("'" + simulatorPath + "' " + arguments); }

  // Built by appending: GCC 12 warns falsely (-Wrestrict) about "literal" + std::string.
  static std::string quoted(const fs::path& path) {
    std::string text(1, '\'');
    text += path.string();
    text += '\'';
    return text;
  }

  /// Starts the simulator with these arguments, stdout to /dev/null and stderr to
  /// errorFile; returns the child's pid.
  static pid_t start(const std::vector<std::string>& arguments, const fs::path& errorFile) {
    const pid_t child = ::fork();
    if (child == 0) {
      const int devNull = ::open("/dev/null", O_WRONLY);
      const int error = ::open(errorFile.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(devNull, STDOUT_FILENO);
      ::dup2(error, STDERR_FILENO);
      std::vector<char*> argv;
      argv.push_back(const_cast<char*>(simulatorPath.c_str()));
      for (const std::string& argument : arguments) argv.push_back(const_cast<char*>(argument.c_str()));
      argv.push_back(nullptr);
      ::execv(simulatorPath.c_str(), argv.data());
      ::_exit(127);
    }
    return child;
  }

  /// Waits (at most 60 s) until output holds at least `frames` complete frames; returns
  /// the count last seen.
  static std::int64_t waitForFrames(const fs::path& output, std::int64_t frames) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    std::int64_t seen = 0;
    while (std::chrono::steady_clock::now() < deadline && seen < frames) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      std::error_code ignored;
      if (fs::exists(output, ignored) && fs::file_size(output, ignored) > 64) {
        try {
          seen = asyncfem::SimulationReader(output).numFrames();
        } catch (const asyncfem::Error&) {
          seen = 0;  // the header itself may be in flight
        }
      }
    }
    return seen;
  }

  /// A run that would go on for a very long time: 6 x 2 x 2 box, pulled, one step per frame.
  static nlohmann::json endlessScene() {
    auto json = smallScene();
    json["mesh"]["cells"] = {6, 2, 2};
    json["mesh"]["size"] = {6, 2, 2};
    json["forces"][0].erase("window");
    json["frames"] = {{"rate", 100}, {"count", 100000000}};
    json["integrator"]["timestep"] = 0.01;
    json["output"]["velocities"] = true;
    return json;
  }

  /// Runs scene uninterrupted for `frames` frames into reference and expects output to
  /// hold exactly the same bytes (and the checkpoints to agree).
  void expectSameAsUninterrupted(const fs::path& scene, std::int64_t frames, const fs::path& output,
                                 const std::string& extra = "") const {
    const fs::path reference = folder_ / "reference.afsim";
    const RunResult r =
        run(quoted(scene) + " --quiet --frames " + std::to_string(frames) + " --output " + quoted(reference) + extra);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const std::string expected = readText(reference);
    const std::string actual = readText(output);
    ASSERT_EQ(expected.size(), actual.size());
    EXPECT_TRUE(expected == actual) << "the resumed run differs from the uninterrupted one";
    EXPECT_TRUE(readText(asyncfem::checkpointPathFor(reference)) == readText(asyncfem::checkpointPathFor(output)));
  }
};

TEST_F(OfflineSimulatorTest, WritesTheRequestedFrames) {
  const fs::path scene = writeScene(smallScene());
  const RunResult r = run(quoted(scene));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  asyncfem::SimulationReader reader(folder_ / "out/run.afsim");  // relative to the scene's folder
  EXPECT_EQ(reader.numFrames(), 6);
  EXPECT_FALSE(reader.hasTruncatedFrame());
  EXPECT_EQ(reader.numVertices(), 16);
  EXPECT_DOUBLE_EQ(reader.header().frameInterval, 0.05);
  EXPECT_DOUBLE_EQ(reader.header().timestep, 0.01);
  EXPECT_FALSE(reader.header().hasVelocities);
  reader.verifyAll();
  for (int k = 0; k < 6; ++k) {
    const asyncfem::SimulationFrame frame = reader.readFrame(k);
    EXPECT_NEAR(frame.time, 0.05 * (k + 1), 1e-12);
    EXPECT_TRUE(frame.displacement.allFinite());
  }
  EXPECT_LT(reader.readFrame(1).displacement.minCoeff(), 0.0);  // pulled down

  // The summary: time split and what was skipped.
  for (const char* expected : {"6 frames", "forces", "assembly", "factorization", "solve", "output",
                               "skipped:", "damping matrix", "corotational", "vtu output", "velocity output"}) {
    EXPECT_NE(r.out.find(expected), std::string::npos) << "missing '" << expected << "' in\n" << r.out;
  }
  // stderr is a file: plain progress lines, no bar redrawn with carriage returns.
  EXPECT_NE(r.err.find("offlineSimulator: frame 6/6 (100%)"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find('\r'), std::string::npos);
}

/// A bar 1 x 0.25 x 0.25 (8 x 2 x 2 cells) fixed at x = 0 whose last quarter, stiff and
/// light, is the fast region "tip" (the asynchronous integrator's test bar), hL = 0.1, one
/// frame. With the paper's coupling its step grows by 1.21657 per large step at m = 32 and
/// shrinks (0.938) at m = 8 (tests/asyncIntegrator/stepGrowthTest.cpp, dense map).
nlohmann::json tipBarScene(const std::string& coupling, int ratio) {
  nlohmann::json scene = nlohmann::json::parse(R"({
    "mesh": {"generator": "box", "size": [1, 0.25, 0.25], "cells": [8, 2, 2],
             "material": {"density": 1000, "youngsModulus": 1e5, "poissonRatio": 0.4},
             "regions": [{"name": "tip", "min": [0.75, -1, -1], "max": [2, 2, 2],
                          "material": {"density": 200, "youngsModulus": 5e6, "poissonRatio": 0.3}}]},
    "fixed": {"sets": ["xmin"]},
    "forces": [{"type": "pull", "set": "xmax", "force": [0, -1, 0], "window": [0, 0.1]}],
    "integrator": {"name": "async", "timestep": 0.1,
                   "options": {"regions": [{"name": "tip", "elementSets": ["tip"]}]}},
    "frames": {"rate": 10, "count": 1},
    "output": {"file": "out/run.afsim"}
  })");
  scene["integrator"]["options"]["regions"][0]["ratio"] = ratio;
  if (!coupling.empty()) scene["integrator"]["options"]["coupling"] = coupling;
  return scene;
}

TEST_F(OfflineSimulatorTest, WarnsWhenThePaperCouplingGrows) {
  const RunResult unstable = run(quoted(writeScene(tipBarScene("paper", 32))));
  ASSERT_EQ(unstable.exitCode, 0) << unstable.err;
  for (const char* expected :
       {"warning", "integrator.options.coupling", "tip (m = 32)", "1.2165", "\"coupling\": \"stable\"", "smaller m"}) {
    EXPECT_NE(unstable.err.find(expected), std::string::npos) << "missing '" << expected << "' in\n" << unstable.err;
  }
  EXPECT_NE(unstable.out.find("stability   paper coupling, tip (m = 32): step growth estimate 1.2165"),
            std::string::npos)
      << unstable.out;

  // Below 1: the estimate in the summary, no warning.
  const RunResult stable = run(quoted(writeScene(tipBarScene("paper", 8))));
  ASSERT_EQ(stable.exitCode, 0) << stable.err;
  EXPECT_EQ(stable.err.find("warning"), std::string::npos) << stable.err;
  EXPECT_NE(stable.out.find("step growth estimate 0.938"), std::string::npos) << stable.out;

  // Skipped on request.
  const RunResult skipped = run(quoted(writeScene(tipBarScene("paper", 32))) + " --no-stability-check");
  ASSERT_EQ(skipped.exitCode, 0) << skipped.err;
  EXPECT_EQ(skipped.err.find("warning"), std::string::npos) << skipped.err;
  EXPECT_EQ(skipped.out.find("stability"), std::string::npos) << skipped.out;
}

// The summary lists the regions the run used (name, vertices, interface DOFs, m) and how
// checkpoints were written (by default every 30 s of wall time, plus the last frame).
TEST_F(OfflineSimulatorTest, SummaryListsTheRegionsAndTheCheckpoints) {
  const RunResult r = run(quoted(writeScene(tipBarScene("stable", 8))));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("regions     1 fast region"), std::string::npos) << r.out;
  // The tip: x >= 0.75 of 8 x 2 x 2 cells, 3 x 3 x 3 lattice planes = 27 vertices; its
  // interface is the x = 0.625 plane of L, 9 vertices, 27 DOFs.
  EXPECT_NE(r.out.find("S_1 'tip': 27 vertices, 27 interface DOFs, m = 8"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("1 checkpoints, every 30 s of wall time and at the end"), std::string::npos) << r.out;
  // The per-frame breakdown never shows a negative remainder (phases timed on several
  // threads at once can add up to more than the wall time; the line then says so).
  const auto other = r.out.find("    other ");
  ASSERT_NE(other, std::string::npos) << r.out;
  const std::string otherLine = r.out.substr(other, r.out.find('\n', other) - other);
  EXPECT_FALSE(std::regex_search(otherLine, std::regex(R"(other\s+-[0-9])"))) << otherLine;
  EXPECT_TRUE(otherLine.find(" ms ") != std::string::npos || otherLine.find("several threads") != std::string::npos)
      << otherLine;
  const RunResult everyFrame = run(quoted(writeScene(smallScene())) + " --checkpoint-every 1 --checkpoint-seconds 0");
  ASSERT_EQ(everyFrame.exitCode, 0) << everyFrame.err;
  EXPECT_NE(everyFrame.out.find("checkpoints, every 1 frame and at the end"), std::string::npos) << everyFrame.out;
  const RunResult single = run(quoted(writeScene(smallScene())));
  EXPECT_EQ(single.out.find("regions "), std::string::npos) << single.out;
}

TEST_F(OfflineSimulatorTest, NoStabilityCheckForTheStableCouplingOrSingleRate) {
  nlohmann::json singleRate = tipBarScene("", 32);
  singleRate["integrator"] = {{"name", "backward-euler"}, {"timestep", 0.1}};
  for (const nlohmann::json& scene : {tipBarScene("stable", 32), singleRate}) {
    const RunResult r = run(quoted(writeScene(scene)));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
    EXPECT_EQ(r.out.find("stability"), std::string::npos) << r.out;
  }
}

TEST_F(OfflineSimulatorTest, CommandLineOverridesTheScene) {
  const fs::path scene = writeScene(smallScene());
  const fs::path output = folder_ / "elsewhere/override.afsim";
  const RunResult r = run(quoted(scene) + " --frames 3 --dt 0.025 --integrator trapezoidal --output " + quoted(output) +
                          " --vtu " + quoted(folder_ / "vtu"));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_FALSE(fs::exists(folder_ / "out/run.afsim"));
  asyncfem::SimulationReader reader(output);
  EXPECT_EQ(reader.numFrames(), 3);
  EXPECT_DOUBLE_EQ(reader.header().timestep, 0.025);
  EXPECT_NE(r.out.find("integrator trapezoidal"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(2 per frame)"), std::string::npos) << r.out;
  for (int k = 0; k < 3; ++k) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.vtu", k);
    EXPECT_TRUE(fs::exists(folder_ / "vtu" / name)) << name;
  }
  EXPECT_FALSE(fs::exists(folder_ / "vtu/frame_00003.vtu"));
}

TEST_F(OfflineSimulatorTest, VelocitiesOnlyWhenRequested) {
  auto json = smallScene();
  json["output"]["velocities"] = true;
  const RunResult r = run(quoted(writeScene(json)) + " --quiet");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_TRUE(r.err.empty()) << r.err;
  asyncfem::SimulationReader reader(folder_ / "out/run.afsim");
  EXPECT_TRUE(reader.header().hasVelocities);
  EXPECT_EQ(reader.readFrame(0).velocity.size(), 48);
}

// output.contactForces: each record and each .vtu carries every vertex's contact force
// (the ground 1 mm above the box's bottom face pushes it up from the first step); a run
// stopped and resumed writes the same bytes, and a resume without the key is refused by it.
TEST_F(OfflineSimulatorTest, ContactForcesGoIntoTheRecordsAndTheVtuFrames) {
  auto json = smallScene();
  json["contact"] = {{"ground", {{"height", 0.001}}}, {"stiffness", 1e4}};
  json["output"]["contactForces"] = true;
  json["output"]["vtu"] = {{"folder", "vtu"}, {"encoding", "ascii"}};
  const fs::path scene = writeScene(json);
  const RunResult r = run(quoted(scene) + " --quiet");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  asyncfem::SimulationReader reader(folder_ / "out/run.afsim");
  EXPECT_TRUE(reader.header().hasContactForces);
  const asyncfem::SimulationFrame frame = reader.readFrame(0);
  ASSERT_EQ(frame.contactForce.size(), 48);
  double up = 0.0;
  for (int v = 0; v < 16; ++v) up += frame.contactForce[(3 * v) + 1];
  EXPECT_GT(up, 0.0);  // the ground pushes up
  EXPECT_NE(readText(folder_ / "vtu/frame_00000.vtu").find("Name=\"contactForce\" NumberOfComponents=\"3\""),
            std::string::npos);
  // Stopped after 3 frames and resumed: the same bytes as the uninterrupted run.
  const fs::path output = folder_ / "out/run.afsim";
  ASSERT_EQ(run(quoted(scene) + " --quiet --frames 3").exitCode, 0);
  ASSERT_EQ(run(quoted(scene) + " --quiet --resume").exitCode, 0);
  expectSameAsUninterrupted(scene, 6, output);
  // The same file continued without the forces: refused, naming the key.
  json["output"]["contactForces"] = false;
  const RunResult refused = run(quoted(writeScene(json)) + " --quiet --resume");
  EXPECT_NE(refused.exitCode, 0);
  EXPECT_NE(refused.err.find("output.contactForces"), std::string::npos) << refused.err;
}

TEST_F(OfflineSimulatorTest, ProgressFlagDrawsTheBar) {
  const RunResult r = run(quoted(writeScene(smallScene())) + " --progress");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find('\r'), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("ETA"), std::string::npos) << r.err;
}

TEST_F(OfflineSimulatorTest, UnstableExplicitRunStopsNamingTheFrame) {
  auto json = smallScene();
  json["mesh"]["material"]["youngsModulus"] = 1e8;
  json["forces"][0].erase("window");
  json["integrator"] = nlohmann::json::parse(R"({"name": "central-differences", "timestep": 0.01,
                                                 "options": {"force": true}})");
  json["frames"] = {{"rate", 100}, {"count", 200}};
  const RunResult r = run(quoted(writeScene(json)));
  ASSERT_NE(r.exitCode, 0);
  const std::size_t at = r.err.find("offlineSimulator: frame ");
  ASSERT_NE(at, std::string::npos) << r.err;
  const int failedFrame = std::stoi(r.err.substr(at + std::string("offlineSimulator: frame ").size()));
  EXPECT_NE(r.err.find("unstable"), std::string::npos) << r.err;
  // It says where: the vertex and that it is one of the (single-rate) mesh.
  EXPECT_NE(r.err.find(" at vertex "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(" of the mesh"), std::string::npos) << r.err;

  // Every frame before the failing one is there, complete and finite; the failing one is not.
  asyncfem::SimulationReader reader(folder_ / "out/run.afsim");
  EXPECT_EQ(reader.numFrames(), failedFrame);
  EXPECT_FALSE(reader.hasTruncatedFrame());
  for (int k = 0; k < reader.numFrames(); ++k) {
    EXPECT_TRUE(reader.readFrame(k).displacement.allFinite()) << "frame " << k;
  }
}

TEST_F(OfflineSimulatorTest, SceneErrorsNameTheKeyAndLeaveOutputAlone) {
  const fs::path output = folder_ / "out/run.afsim";
  fs::create_directories(output.parent_path());
  std::ofstream(output) << "previous results";
  auto json = smallScene();
  json["forces"][0]["window"] = {0.5, 0.1};
  const RunResult r = run(quoted(writeScene(json)));
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("offlineSimulator: " + (folder_ / "scene.json").string() +
                       ": forces[0].window: expected [start, end] with start <= end"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(readText(output), "previous results");

  json = smallScene();
  json["output"].erase("file");
  const RunResult noOutput = run(quoted(writeScene(json)));
  EXPECT_EQ(noOutput.exitCode, 1);
  EXPECT_NE(noOutput.err.find("offlineSimulator: no output file"), std::string::npos) << noOutput.err;

  const RunResult missing = run(quoted(folder_ / "missing.json"));
  EXPECT_EQ(missing.exitCode, 1);
  EXPECT_EQ(missing.err.rfind("offlineSimulator: ", 0), 0U) << missing.err;

  const RunResult badOption = run(quoted(writeScene(smallScene())) + " --dt -1");
  EXPECT_NE(badOption.exitCode, 0);
  EXPECT_EQ(badOption.err.rfind("offlineSimulator: ", 0), 0U) << badOption.err;
}

// --dt must divide the frame interval (to a relative 1e-9); the refusal names the frame
// interval and the two nearest valid timesteps, and --steps-per-frame gives one of them.
TEST_F(OfflineSimulatorTest, TimestepMustDivideTheFrameOrBeGivenAsStepsPerFrame) {
  const fs::path scene = writeScene(smallScene());  // frames.rate 20
  const RunResult refused = run(quoted(scene) + " --dt 0.003");
  EXPECT_EQ(refused.exitCode, 1);
  EXPECT_NE(refused.err.find("offlineSimulator: " + scene.string() +
                             ": integrator.timestep: 0.003 does not divide the frame interval 1/20 s (frames.rate 20) "
                             "into whole steps: 16.6666666667 steps per frame; the nearest valid timesteps are 1/320 s "
                             "= 0.003125 s (16 steps per frame) and 1/340 s = 0.00294117647 s (17 steps per frame)"),
            std::string::npos)
      << refused.err;
  EXPECT_FALSE(fs::exists(folder_ / "out/run.afsim"));

  const RunResult bySteps = run(quoted(scene) + " --steps-per-frame 16 --frames 2");
  EXPECT_EQ(bySteps.exitCode, 0) << bySteps.err;
  EXPECT_NE(bySteps.out.find("32 steps of h = 0.003125 (16 per frame)"), std::string::npos) << bySteps.out;
  const RunResult nearDivisor = run(quoted(scene) + " --dt 0.0031250000001 --frames 2");
  EXPECT_EQ(nearDivisor.exitCode, 0) << nearDivisor.err;

  const RunResult both = run(quoted(scene) + " --dt 0.01 --steps-per-frame 5");
  EXPECT_EQ(both.exitCode, 2);
  EXPECT_EQ(both.err.rfind("offlineSimulator: ", 0), 0U) << both.err;
  const RunResult zero = run(quoted(scene) + " --steps-per-frame 0");
  EXPECT_EQ(zero.exitCode, 2);
  EXPECT_NE(zero.err.find("offlineSimulator: --steps-per-frame: must be >= 1 (got 0) (see --help)"), std::string::npos)
      << zero.err;
}

// README's command: an async scene run with --integrator backward-euler drops (and names)
// the async options and runs; naming the scene's own integrator drops nothing.
TEST_F(OfflineSimulatorTest, IntegratorSwapDropsTheOptionsItDoesNotRead) {
  auto json = smallScene();
  json["integrator"] = nlohmann::json::parse(R"({"name": "async", "timestep": 0.01, "options": {
      "regions": [{"name": "tip", "ratio": 4, "vertexSets": ["xmax"]}]}})");
  const fs::path scene = writeScene(json);
  const RunResult swapped = run(quoted(scene) + " --integrator backward-euler --frames 2");
  EXPECT_EQ(swapped.exitCode, 0) << swapped.err;
  EXPECT_NE(swapped.err.find("offlineSimulator: --integrator backward-euler: dropped the scene's integrator.options "
                             "regions (not read by backward-euler)"),
            std::string::npos)
      << swapped.err;
  const RunResult same = run(quoted(scene) + " --integrator async --frames 2");
  EXPECT_EQ(same.exitCode, 0) << same.err;
  EXPECT_EQ(same.err.find("dropped"), std::string::npos) << same.err;
}

// An output that is one of the run's inputs (the scene, the mesh), however it is spelled,
// is refused before anything is written.
TEST_F(OfflineSimulatorTest, RefusesToWriteOverItsInputs) {
  auto json = smallScene();
  const fs::path mesh = folder_ / "box.veg";
  const fs::path scene = writeScene(json);
  const std::string sceneText = readText(scene);
  const RunResult same = run(quoted(scene) + " --output " + quoted(scene));
  EXPECT_EQ(same.exitCode, 1);
  EXPECT_NE(same.err.find("offlineSimulator: the output file " + scene.string() + " is the scene " + scene.string() +
                          ": writing it would destroy the input"),
            std::string::npos)
      << same.err;
  fs::create_symlink(scene, folder_ / "link.json");
  const RunResult throughLink = run(quoted(scene) + " --output " + quoted(folder_ / "sub/../link.json"));
  EXPECT_EQ(throughLink.exitCode, 1);
  EXPECT_NE(throughLink.err.find("is the scene"), std::string::npos) << throughLink.err;
  EXPECT_EQ(readText(scene), sceneText);

  // A mesh file: the output may not be it either.
  const std::string veg =
      "*VERTICES\n4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n*ELEMENTS\nTET\n1 0 0\n"
      "1 1 2 3 4\n*MATERIAL m\nENU, 1000, 1e5, 0.4\n*REGION\nallElements, m\n";
  std::ofstream(mesh) << veg;
  json["mesh"] = {{"file", "box.veg"}};
  json["fixed"] = {{"boxes", {{{"min", {0, 0, 0}}, {"max", {0, 0, 0}}}}}};
  json["forces"] = nlohmann::json::array();
  const fs::path meshScene = writeScene(json, "mesh.json");
  const RunResult overMesh = run(quoted(meshScene) + " --output " + quoted(folder_ / "./box.veg"));
  EXPECT_EQ(overMesh.exitCode, 1);
  EXPECT_NE(overMesh.err.find("is the mesh " + mesh.string()), std::string::npos) << overMesh.err;
  EXPECT_EQ(readText(mesh), veg);
}

// Usage errors print "offlineSimulator: message (see --help)" and exit with status 2.
TEST_F(OfflineSimulatorTest, UsageErrorsAreReadable) {
  const fs::path scene = writeScene(smallScene());
  const RunResult negative = run(quoted(scene) + " --dt -0.5");
  EXPECT_EQ(negative.exitCode, 2);
  EXPECT_EQ(negative.err, "offlineSimulator: --dt: must be > 0 (got -0.5) (see --help)\n");
  const RunResult folder = run(quoted(folder_));
  EXPECT_EQ(folder.exitCode, 1);
  EXPECT_NE(folder.err.find("is a directory, not a scene file"), std::string::npos) << folder.err;
}

TEST_F(OfflineSimulatorTest, KilledRunLeavesEveryFinishedFrameReadable) {
  auto json = smallScene();
  json["mesh"]["cells"] = {6, 2, 2};
  json["mesh"]["size"] = {6, 2, 2};
  json["forces"][0].erase("window");
  json["frames"] = {{"rate", 100}, {"count", 100000000}};
  json["integrator"]["timestep"] = 0.01;
  const fs::path scene = writeScene(json);
  const fs::path output = folder_ / "out/run.afsim";

  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const int devNull = ::open("/dev/null", O_WRONLY);
    ::dup2(devNull, STDOUT_FILENO);
    ::dup2(devNull, STDERR_FILENO);
    const std::string sceneArgument = scene.string();
    ::execl(simulatorPath.c_str(), simulatorPath.c_str(), sceneArgument.c_str(), "--quiet",
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  // Wait until some frames are on disk (at most 60 s), then kill without warning.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  std::int64_t seen = 0;
  while (std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    std::error_code ignored;
    if (fs::exists(output, ignored) && fs::file_size(output, ignored) > 64) {
      try {
        seen = asyncfem::SimulationReader(output).numFrames();
      } catch (const asyncfem::Error&) {
        seen = 0;  // the header itself may be in flight
      }
      if (seen >= 5) {
        break;
      }
    }
  }
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the run ended before it was killed";
  ASSERT_GE(seen, 5) << "no frames appeared within 60 s";

  asyncfem::SimulationReader reader(output);
  EXPECT_GE(reader.numFrames(), seen);
  EXPECT_NO_THROW(reader.verifyAll());
  for (std::int64_t k = 0; k < reader.numFrames(); ++k) {
    EXPECT_NEAR(reader.readFrame(k).time, 0.01 * static_cast<double>(k + 1), 1e-9);
  }
}

TEST_F(OfflineSimulatorTest, ResumedRunIsBitIdenticalForEveryIntegrator) {
  // Each integrator's full state (u, v, t and, for the trapezoidal rule and central
  // differences, the acceleration) goes through the checkpoint.
  const std::vector<std::pair<std::string, nlohmann::json>> integrators = {
      {"backward-euler", nlohmann::json::parse(R"({"name": "backward-euler", "timestep": 0.01})")},
      {"trapezoidal", nlohmann::json::parse(R"({"name": "trapezoidal", "timestep": 0.01})")},
      {"central-differences", nlohmann::json::parse(R"({"name": "central-differences", "timestep": 0.001})")},
      {"symplectic-euler", nlohmann::json::parse(R"({"name": "symplectic-euler", "timestep": 0.001})")},
      {"async", nlohmann::json::parse(R"({"name": "async", "timestep": 0.01,
          "options": {"regions": [{"name": "tip", "ratio": 4, "vertexSets": ["xmax"]}]}})")},
      {"corotational", nlohmann::json::parse(R"({"name": "trapezoidal", "timestep": 0.05,
                                                 "options": {"maxIterations": 3}})")},
  };
  for (const auto& [label, integrator] : integrators) {
    SCOPED_TRACE(label);
    auto json = smallScene();
    json["integrator"] = integrator;
    json["output"]["velocities"] = true;
    if (label == "corotational") {
      json["forceModel"] = {{"type", "corotational"}};
    }
    const fs::path scene = writeScene(json, label + ".json");
    const fs::path output = folder_ / (label + ".afsim");
    const RunResult first = run(quoted(scene) + " --quiet --frames 4 --output " + quoted(output));
    ASSERT_EQ(first.exitCode, 0) << first.err;
    const RunResult resumed = run(quoted(scene) + " --frames 9 --resume --output " + quoted(output));
    ASSERT_EQ(resumed.exitCode, 0) << resumed.err;
    EXPECT_NE(resumed.out.find("5 frames (resumed after frame 4 of 9)"), std::string::npos) << resumed.out;
    expectSameAsUninterrupted(scene, 9, output);
  }
}

TEST_F(OfflineSimulatorTest, ResumeWithTheKeptFactorIsBitIdentical) {
  // reuseFactor (the default for nonlinear models) keeps a factor across steps and frames
  // as PCG preconditioner; the checkpoint holds what rebuilds it (BackwardEuler::
  // internalState()), so a run resumed at a checkpoint continues bit for bit, with no
  // "resume:" caveat. The run must really reuse (PCG iterations reported), or the
  // comparison would not cover it.
  auto json = smallScene();
  json["mesh"]["cells"] = {6, 2, 2};
  json["forceModel"] = {{"type", "corotational"}};
  json["forces"][0]["force"] = {0, -2000, 0};
  json["frames"]["count"] = 10;
  for (const bool reuse : {true, false}) {
    SCOPED_TRACE(reuse ? "reuseFactor" : "exact");
    json["integrator"]["options"] = {{"reuseFactor", reuse}};
    const std::string name = reuse ? "reuse" : "exact";
    const fs::path scene = writeScene(json, name + ".json");
    const fs::path output = folder_ / (name + ".afsim");
    const RunResult first = run(quoted(scene) + " --frames 4 --checkpoint-every 1 --output " + quoted(output));
    ASSERT_EQ(first.exitCode, 0) << first.err;
    EXPECT_NE(first.out.find(reuse ? "kept factor as PCG preconditioner" : "linear solves: exact"), std::string::npos)
        << first.out;
    if (reuse) {
      EXPECT_EQ(first.out.find(" 0 PCG iterations per step"), std::string::npos) << first.out;
    }
    const RunResult resumed = run(quoted(scene) + " --frames 10 --resume --output " + quoted(output));
    ASSERT_EQ(resumed.exitCode, 0) << resumed.err;
    EXPECT_EQ(resumed.out.find("resume:"), std::string::npos) << resumed.out;
    expectSameAsUninterrupted(scene, 10, output);
  }
}

// The number in the summary line "... N factorizations in M steps ..." (the kept factor's
// report) and in "(N factorizations in the run)"; -1 when missing.
long long countBefore(const std::string& text, const std::string& after) {
  const std::size_t end = text.find(after);
  if (end == std::string::npos || end == 0) return -1;
  std::size_t start = end;
  while (start > 0 && std::isdigit(static_cast<unsigned char>(text[start - 1])) != 0) --start;
  return start == end ? -1 : std::stoll(text.substr(start, end - start));
}

TEST_F(OfflineSimulatorTest, KeptFactorLivesAcrossFramesOfOneStepAndResumesBitIdentically) {
  // One step per frame, as graphics scenes at 30 or 60 frames per second often are: the
  // default nonlinear backward Euler keeps its factor from frame to frame (it once
  // refactored at every frame start, so that a resumed run would be bit-identical: as many
  // factorizations as frames). Now it factors fewer times than it has frames, and a run
  // resumed from any frame's checkpoint (every frame's, and a killed run's) still writes
  // exactly the uninterrupted run's bytes.
  auto json = smallScene();
  json["mesh"]["cells"] = {6, 2, 2};
  json["forceModel"] = {{"type", "corotational"}, {"tangent", "exact"}};
  json["forces"][0]["force"] = {0, -2000, 0};
  json["forces"][0]["window"] = {0, 0.08};
  json["frames"] = {{"rate", 100}, {"count", 24}};  // h = 0.01: one step per frame
  json["output"]["velocities"] = true;
  const fs::path scene = writeScene(json, "oneStep.json");
  const fs::path output = folder_ / "oneStep.afsim";
  const RunResult whole = run(quoted(scene) + " --output " + quoted(output));
  ASSERT_EQ(whole.exitCode, 0) << whole.err;
  EXPECT_NE(whole.out.find("24 steps of h = 0.01 (1 per frame)"), std::string::npos) << whole.out;
  const long long factorizations = countBefore(whole.out, " factorizations in 24 steps");
  EXPECT_GE(factorizations, 1) << whole.out;
  EXPECT_LT(factorizations, 24) << whole.out;
  EXPECT_EQ(countBefore(whole.out, " factorizations in the run)"), factorizations) << whole.out;
  EXPECT_EQ(whole.out.find(" 0 PCG iterations per step"), std::string::npos) << whole.out;
  for (const int stopAt : {5, 11, 16}) {
    SCOPED_TRACE("stopped after frame " + std::to_string(stopAt));
    const RunResult first = run(quoted(scene) + " --quiet --checkpoint-every 1 --frames " + std::to_string(stopAt) +
                                " --output " + quoted(output));
    ASSERT_EQ(first.exitCode, 0) << first.err;
    const RunResult resumed = run(quoted(scene) + " --resume --output " + quoted(output));
    ASSERT_EQ(resumed.exitCode, 0) << resumed.err;
    EXPECT_EQ(resumed.out.find("resume:"), std::string::npos) << resumed.out;
    // The resumed run factors the kept factor's matrix once, and no more than it needs.
    EXPECT_LT(countBefore(resumed.out, " factorizations in the run)"), 24 - stopAt) << resumed.out;
    expectSameAsUninterrupted(scene, 24, output);
  }
}

TEST_F(OfflineSimulatorTest, VersionTwoCheckpointOfTheKeptFactorStillResumesAndSaysHow) {
  // A checkpoint written before format version 3 holds no kept-factor state (that run
  // refactored at every frame start): the resume refactors at its first step, prints a
  // "resume:" caveat and stays within the PCG tolerance's reach of the uninterrupted run.
  auto json = smallScene();
  json["mesh"]["cells"] = {6, 2, 2};
  json["forceModel"] = {{"type", "corotational"}};
  json["forces"][0]["force"] = {0, -2000, 0};
  json["frames"] = {{"rate", 100}, {"count", 12}};
  const fs::path scene = writeScene(json, "versionTwo.json");
  const fs::path output = folder_ / "versionTwo.afsim";
  ASSERT_EQ(run(quoted(scene) + " --quiet --frames 5 --output " + quoted(output)).exitCode, 0);
  // The same checkpoint as version 2 wrote it: no internal state, version field 2.
  const fs::path checkpointFile = asyncfem::checkpointPathFor(output);
  asyncfem::SimulationCheckpoint checkpoint = asyncfem::readCheckpoint(checkpointFile);
  ASSERT_GT(checkpoint.internalState.size(), 0);
  checkpoint.internalState.resize(0);
  asyncfem::writeCheckpoint(checkpointFile, checkpoint);
  std::string bytes = readText(checkpointFile);
  bytes[8] = 2;
  const auto putCrc = [&](std::size_t offset, std::size_t length) {
    const std::uint32_t crc = asyncfem::crc32(bytes.data(), length);
    for (std::size_t b = 0; b < 4; ++b) bytes[offset + b] = static_cast<char>((crc >> (8 * b)) & 0xffU);
  };
  putCrc(60, 60);
  putCrc(bytes.size() - 8, bytes.size() - 8);
  std::ofstream(checkpointFile, std::ios::binary) << bytes;
  const RunResult resumed = run(quoted(scene) + " --resume --output " + quoted(output));
  ASSERT_EQ(resumed.exitCode, 0) << resumed.err;
  EXPECT_NE(resumed.out.find("resume: the checkpoint holds no kept-factor state"), std::string::npos) << resumed.out;
  const fs::path reference = folder_ / "versionTwoReference.afsim";
  ASSERT_EQ(run(quoted(scene) + " --quiet --output " + quoted(reference)).exitCode, 0);
  asyncfem::SimulationReader a(output);
  asyncfem::SimulationReader b(reference);
  ASSERT_EQ(a.numFrames(), 12);
  const Eigen::VectorXd last = b.readFrame(11).displacement;
  EXPECT_LT((a.readFrame(11).displacement - last).cwiseAbs().maxCoeff(), 1e-6 * last.cwiseAbs().maxCoeff());
}

TEST_F(OfflineSimulatorTest, SignalStopsAfterTheFrameAndTheRunResumesBitIdentically) {
  const fs::path scene = writeScene(endlessScene());
  const fs::path output = folder_ / "out/run.afsim";
  for (const int signal : {SIGINT, SIGTERM}) {
    SCOPED_TRACE(signal == SIGINT ? "SIGINT" : "SIGTERM");
    const fs::path errorFile = folder_ / "interrupted.txt";
    fs::remove(output);  // so that the frames waited for are this run's
    const pid_t child = start({scene.string()}, errorFile);
    ASSERT_GT(child, 0);
    const std::int64_t seen = waitForFrames(output, 5);
    ::kill(child, signal);
    int status = 0;
    ::waitpid(child, &status, 0);
    ASSERT_GE(seen, 5) << "no frames appeared within 60 s";
    // A clean stop: the exit status says which signal, the message how to go on.
    ASSERT_TRUE(WIFEXITED(status)) << "the simulator did not handle the signal";
    EXPECT_EQ(WEXITSTATUS(status), 128 + signal);
    const std::string message = readText(errorFile);
    EXPECT_NE(message.find(signal == SIGINT ? "interrupted by SIGINT" : "interrupted by SIGTERM"), std::string::npos)
        << message;
    EXPECT_NE(message.find("frames are complete in " + output.string()), std::string::npos) << message;
    EXPECT_NE(message.find("--resume"), std::string::npos) << message;

    // Every frame is complete (no partial record), and the checkpoint is at the last one.
    asyncfem::SimulationReader reader(output);
    EXPECT_FALSE(reader.hasTruncatedFrame());
    EXPECT_NO_THROW(reader.verifyAll());
    const std::int64_t frames = reader.numFrames();
    EXPECT_GE(frames, seen);
    EXPECT_NE(message.find(std::to_string(frames) + " of 100000000 frames are complete"), std::string::npos) << message;
    EXPECT_EQ(asyncfem::readCheckpoint(asyncfem::checkpointPathFor(output)).frames, frames);

    const RunResult resumed = run(quoted(scene) + " --quiet --resume --frames " + std::to_string(frames + 3));
    ASSERT_EQ(resumed.exitCode, 0) << resumed.err;
    expectSameAsUninterrupted(scene, frames + 3, output);
  }
}

TEST_F(OfflineSimulatorTest, KilledRunResumesFromItsLastCheckpoint) {
  // Checkpoints every 7 frames: the frames after the last one are recomputed on resume.
  const fs::path scene = writeScene(endlessScene());
  const fs::path output = folder_ / "out/run.afsim";
  const pid_t child = start({scene.string(), "--checkpoint-every", "7"}, folder_ / "killed.txt");
  ASSERT_GT(child, 0);
  const std::int64_t seen = waitForFrames(output, 10);
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the run ended before it was killed";
  ASSERT_GE(seen, 10) << "no frames appeared within 60 s";
  const std::int64_t checkpointed = asyncfem::readCheckpoint(asyncfem::checkpointPathFor(output)).frames;
  EXPECT_EQ(checkpointed % 7, 0);
  EXPECT_LE(checkpointed, asyncfem::SimulationReader(output).numFrames());

  const std::int64_t frames = asyncfem::SimulationReader(output).numFrames() + 2;
  const RunResult resumed = run(quoted(scene) + " --resume --checkpoint-every 7 --frames " + std::to_string(frames));
  ASSERT_EQ(resumed.exitCode, 0) << resumed.err;
  EXPECT_NE(resumed.out.find("(resumed after frame " + std::to_string(checkpointed) + " of "), std::string::npos)
      << resumed.out;
  expectSameAsUninterrupted(scene, frames, output, " --checkpoint-every 7");
}

/// The sets of vertices whose recorded step ratio is above 1, per frame of file.
std::vector<std::vector<int>> fastVertexSets(const fs::path& file) {
  asyncfem::SimulationReader reader(file);
  std::vector<std::vector<int>> sets;
  for (std::int64_t k = 0; k < reader.numFrames(); ++k) {
    const asyncfem::SimulationFrame frame = reader.readFrame(k);
    std::vector<int> fast;
    for (std::size_t v = 0; v < frame.regionRatios.size(); ++v) {
      if (frame.regionRatios[v] > 1) fast.push_back(static_cast<int>(v));
    }
    sets.push_back(fast);
  }
  return sets;
}

// models/ball: adaptive contact regions, recorded by default. The ball touches the ground
// after 12 frames and its fast region follows the contact patch; a run resumed after frame
// 10 keeps writing records with ratios, and a run without them cannot continue the file.
TEST_F(OfflineSimulatorTest, BallRecordsItsMovingFastRegionAndResumeKeepsTheFlag) {
  nlohmann::json json = nlohmann::json::parse(readText(fs::path(ASYNCFEM_MODELS_DIR) / "ball/ball.json"));
  json["mesh"]["file"] = (fs::path(ASYNCFEM_MODELS_DIR) / "ball/ball.veg").string();
  const fs::path scene = writeScene(json, "ball.json");
  const fs::path output = folder_ / "ball.afsim";
  ASSERT_EQ(run(quoted(scene) + " --quiet --frames 10 --output " + quoted(output)).exitCode, 0);
  const RunResult resumed = run(quoted(scene) + " --quiet --resume --frames 15 --output " + quoted(output));
  ASSERT_EQ(resumed.exitCode, 0) << resumed.err;
  {
    asyncfem::SimulationReader reader(output);
    EXPECT_TRUE(reader.header().hasRegionRatios);
    EXPECT_EQ(reader.numFrames(), 15);
    reader.verifyAll();
  }
  std::vector<std::vector<int>> distinct;
  for (const std::vector<int>& fast : fastVertexSets(output)) {
    if (!fast.empty() && std::find(distinct.begin(), distinct.end(), fast) == distinct.end()) distinct.push_back(fast);
  }
  EXPECT_GE(distinct.size(), 2U) << "the fast region should change between frames as the contact patch grows";

  json["output"] = {{"regions", false}};
  writeScene(json, "ball.json");
  const RunResult refused = run(quoted(scene) + " --quiet --resume --frames 16 --output " + quoted(output));
  EXPECT_EQ(refused.exitCode, 1);
  EXPECT_NE(refused.err.find("ball.afsim: cannot continue it: its header differs from this run's: its records carry "
                             "region ratios (header flag bit 1) but this run's do not (output.regions)"),
            std::string::npos)
      << refused.err;
  EXPECT_EQ(asyncfem::SimulationReader(output).numFrames(), 15);
}

TEST_F(OfflineSimulatorTest, ResumeRefusesWhatItCannotContinueExactly) {
  auto json = smallScene();
  const fs::path scene = writeScene(json);
  const fs::path output = folder_ / "out/run.afsim";
  const fs::path checkpoint = asyncfem::checkpointPathFor(output);
  ASSERT_EQ(run(quoted(scene) + " --quiet --frames 3").exitCode, 0);
  const std::string threeFrames = readText(output);

  // Nothing left to do: the file stays as it is.
  const RunResult same = run(quoted(scene) + " --quiet --resume --frames 3");
  EXPECT_EQ(same.exitCode, 0) << same.err;
  EXPECT_TRUE(readText(output) == threeFrames);

  const RunResult fewer = run(quoted(scene) + " --resume --frames 2");
  EXPECT_EQ(fewer.exitCode, 1);
  EXPECT_NE(fewer.err.find("already has 3 finished frames, more than the 2 requested"), std::string::npos) << fewer.err;

  json["mesh"]["material"]["youngsModulus"] = 2e5;
  const RunResult changed = run(quoted(writeScene(json)) + " --resume --frames 6");
  EXPECT_EQ(changed.exitCode, 1);
  EXPECT_NE(changed.err.find("were written by a different run: the scene file or the mesh it builds"),
            std::string::npos)
      << changed.err;
  // Named fields say what differs, there (the stored run) and here.
  const RunResult otherStep = run(quoted(scene) + " --resume --frames 6 --dt 0.005");
  EXPECT_EQ(otherStep.exitCode, 1);
  EXPECT_NE(otherStep.err.find("were written by a different run: timestep (0.01 there, 0.005 here)"), std::string::npos)
      << otherStep.err;
  const RunResult otherIntegrator = run(quoted(scene) + " --resume --frames 6 --integrator trapezoidal");
  EXPECT_EQ(otherIntegrator.exitCode, 1);
  EXPECT_NE(otherIntegrator.err.find("integrator (backward-euler there, trapezoidal here)"), std::string::npos)
      << otherIntegrator.err;
  EXPECT_TRUE(readText(output) == threeFrames);

  // A corrupted checkpoint is named, and so is a missing one.
  std::string bytes = readText(checkpoint);
  bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 1);
  std::ofstream(checkpoint, std::ios::binary) << bytes;
  const RunResult corrupted = run(quoted(scene) + " --resume --frames 6");
  EXPECT_EQ(corrupted.exitCode, 1);
  EXPECT_NE(corrupted.err.find(checkpoint.string() + ": checkpoint checksum mismatch"), std::string::npos)
      << corrupted.err;
  fs::remove(checkpoint);
  const RunResult missing = run(quoted(scene) + " --resume --frames 6");
  EXPECT_EQ(missing.exitCode, 1);
  EXPECT_NE(missing.err.find("cannot resume: no checkpoint"), std::string::npos) << missing.err;
  EXPECT_NE(missing.err.find("run without --resume to start over"), std::string::npos) << missing.err;
  EXPECT_TRUE(readText(output) == threeFrames);
}

}  // namespace

namespace {

// Every scene shipped in models/ and the benchmark scenes in tests/benchmarks/scenes run
// through the simulator as a user would start them (comments, relative mesh paths and
// all): two frames, exit 0, two finite frames written.
TEST_F(OfflineSimulatorTest, EveryShippedSceneRuns) {
  int scenes = 0;
  std::vector<fs::path> folders{fs::path(ASYNCFEM_TEST_DATA_DIR).parent_path() / "benchmarks" / "scenes"};
  for (const auto& folder : fs::directory_iterator(ASYNCFEM_MODELS_DIR)) {
    if (folder.is_directory()) folders.push_back(folder.path());
  }
  for (const fs::path& folder : folders) {
    for (const auto& entry : fs::directory_iterator(folder)) {
      if (entry.path().extension() != ".json") continue;
      ++scenes;
      const fs::path output = folder_ / (entry.path().stem().string() + ".afsim");
      const RunResult result = run(quoted(entry.path()) + " --frames 2 --quiet --output " + quoted(output));
      ASSERT_EQ(result.exitCode, 0) << entry.path() << "\n" << result.err;
      asyncfem::SimulationReader reader(output);
      EXPECT_EQ(reader.numFrames(), 2) << entry.path();
    }
  }
  EXPECT_GE(scenes, 4);  // at least the default scene, its single-rate twin and the two benchmark scenes
}

}  // namespace

namespace {

/// The (timestep, file) pairs of a .pvd, in order.
std::vector<std::pair<double, std::string>> pvdEntries(const fs::path& path) {
  const std::string text = readText(path);
  std::vector<std::pair<double, std::string>> entries;
  const std::string timeKey = "timestep=\"";
  const std::string fileKey = "file=\"";
  for (std::size_t at = text.find("<DataSet"); at != std::string::npos; at = text.find("<DataSet", at + 1)) {
    const std::size_t time = text.find(timeKey, at) + timeKey.size();
    const std::size_t file = text.find(fileKey, at) + fileKey.size();
    entries.emplace_back(std::stod(text.substr(time, text.find('"', time) - time)),
                         text.substr(file, text.find('"', file) - file));
  }
  return entries;
}

// Every vtu.every-th frame becomes a binary .vtu, listed in frames.pvd at the time the
// .afsim record holds; a run stopped early and resumed leaves the same collection as an
// uninterrupted one; "encoding": "ascii" writes text.
TEST_F(OfflineSimulatorTest, VtuFramesComeWithAPvdCollection) {
  auto json = smallScene();
  json["output"]["vtu"] = {{"folder", "vtu"}, {"every", 2}};
  const fs::path scene = writeScene(json);
  const RunResult full = run(quoted(scene) + " --quiet");
  ASSERT_EQ(full.exitCode, 0) << full.err;
  const auto entries = pvdEntries(folder_ / "vtu/frames.pvd");
  asyncfem::SimulationReader reader(folder_ / "out/run.afsim");
  ASSERT_EQ(entries.size(), 3U);
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const auto frame = static_cast<std::int64_t>(2 * i);
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.vtu", static_cast<int>(frame));
    EXPECT_EQ(entries[i].second, name);
    EXPECT_EQ(entries[i].first, reader.readFrame(frame).time);  // printed in the shortest exact form
    const std::string vtu = readText(folder_ / "vtu" / name);
    EXPECT_NE(vtu.find("header_type=\"UInt64\""), std::string::npos);
    EXPECT_NE(vtu.find("<AppendedData encoding=\"raw\">"), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(folder_ / "vtu/frames.pvd.tmp"));

  // Stopped after 3 frames: the collection lists the two .vtu files written so far.
  fs::remove_all(folder_ / "vtu");
  ASSERT_EQ(run(quoted(scene) + " --quiet --frames 3").exitCode, 0);
  const auto partial = pvdEntries(folder_ / "vtu/frames.pvd");
  ASSERT_EQ(partial.size(), 2U);
  EXPECT_EQ(partial[1].second, "frame_00002.vtu");
  const RunResult resumed = run(quoted(scene) + " --quiet --resume");
  ASSERT_EQ(resumed.exitCode, 0) << resumed.err;
  EXPECT_EQ(pvdEntries(folder_ / "vtu/frames.pvd"), entries);

  json["output"]["vtu"]["encoding"] = "ascii";
  ASSERT_EQ(run(quoted(writeScene(json)) + " --quiet").exitCode, 0);
  const std::string ascii = readText(folder_ / "vtu/frame_00000.vtu");
  EXPECT_NE(ascii.find("Name=\"displacement\" NumberOfComponents=\"3\" format=\"ascii\""), std::string::npos);
  EXPECT_EQ(ascii.find("AppendedData"), std::string::npos);
}

// The scene's .vtu folder follows --output (OUT.afsim -> OUT_vtu/): two runs of one scene
// with different outputs keep two series; --vtu still chooses the folder.
TEST_F(OfflineSimulatorTest, VtuFolderFollowsTheOutput) {
  auto json = smallScene();
  json["output"]["vtu"] = {{"folder", "vtu"}};
  const fs::path scene = writeScene(json);
  for (const char* name : {"a", "b"}) {
    const RunResult r = run(quoted(scene) + " --quiet --output " + quoted(folder_ / name) + ".afsim");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(fs::exists(folder_ / (std::string(name) + "_vtu") / "frames.pvd")) << name;
  }
  EXPECT_FALSE(fs::exists(folder_ / "vtu"));
  const RunResult chosen =
      run(quoted(scene) + " --quiet --output " + quoted(folder_ / "c.afsim") + " --vtu " + quoted(folder_ / "mine"));
  ASSERT_EQ(chosen.exitCode, 0) << chosen.err;
  EXPECT_TRUE(fs::exists(folder_ / "mine" / "frames.pvd"));
  EXPECT_FALSE(fs::exists(folder_ / "c_vtu"));
}

}  // namespace
