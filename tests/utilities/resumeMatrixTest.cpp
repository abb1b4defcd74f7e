// SPDX-License-Identifier: BSD-3-Clause
// The resume matrix (docs/robustness.md, "The resume matrix"): every integrator x every
// force model x every option that keeps state between steps, stopped by SIGINT or killed
// with SIGKILL at a frame drawn from a seeded generator, then resumed with --resume. The
// resumed file must equal an uninterrupted run bit for bit or, where the simulator said
// stated bound of it where the test knows a state that no checkpoint holds (the kept Schur
// factor of a nonlinear asynchronous run, the quick set-up's progress, implicit contact's
// blocks): the test chooses the oracle from the case, and such a case must also have been
// announced by the simulator before resuming (a "resume:" line).
//
// ctest runs a seeded subset (instantiation "Seeded": every integrator, force model and
// option at least once); the whole matrix is the instantiation "Full", run with
//   build/bin/resumeMatrixTests --gtest_filter='Full/*'
// or, configured with -DASYNCFEM_RESUME_MATRIX_FULL=ON, `ctest -L resume-matrix-full`.
// ASYNCFEM_RESUME_MATRIX_SEED=N draws other interruption frames (and another subset).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "resumeHarness.hpp"

namespace {

namespace fs = std::filesystem;

const std::string simulatorPath = std::string(ASYNCFEM_BIN_DIR) + "/offlineSimulator";

using asyncfem::test::Child;
using asyncfem::test::compareFrames;
using asyncfem::test::Difference;
using asyncfem::test::matrixSeed;
using asyncfem::test::readText;
using asyncfem::test::stableHash;

/// One combination: integrator, force model, stateful option, how the run is stopped.
struct MatrixCase {
  std::string integrator;  ///< backwardEuler, trapezoidal, ..., multirateUncoupled, schroeder2011, asyncNested
  std::string model;       ///< linear, corotational, stvk, neoHookean, mooneyRivlin
  /// plain, lineSearch, reuseFactor, exactSolves, noLaggedSchur, contact, substepStatePrediction,
  /// implicitContact, quickSetUp, schedule, proposedRegions
  std::string option;
  bool kill9 = false;  ///< SIGKILL instead of SIGINT

  std::string name() const { return integrator + "_" + model + "_" + option + (kill9 ? "_kill9" : "_sigint"); }
};

// gtest prints a parameter in test listings and failures: the case's name.
void PrintTo(const MatrixCase& c, std::ostream* out) { *out << c.name(); }

const std::vector<std::string> integrators = {"backwardEuler",      "trapezoidal",   "centralDifferences",
                                              "symplecticEuler",    "asyncStable",   "asyncPaper",
                                              "multirateUncoupled", "schroeder2011", "asyncNested"};
const std::vector<std::string> models = {"linear", "corotational", "stvk", "neoHookean", "mooneyRivlin"};

bool isAsync(const std::string& integrator) {
  return integrator == "asyncStable" || integrator == "asyncPaper" || integrator == "asyncNested";
}

/// The options an integrator reads that keep state between steps (or change how a step
/// is solved); combinations where the option does nothing are not generated.
std::vector<std::string> optionsFor(const std::string& integrator, const std::string& model) {
  const bool nonlinear = model != "linear";
  std::vector<std::string> options = {"plain", "contact"};
  if (integrator == "backwardEuler" && nonlinear) {
    options.emplace_back("lineSearch");
    options.emplace_back("reuseFactor");  // the default kept factor, linearized steps
    options.emplace_back("exactSolves");  // reuseFactor off: one factorization per iteration
  }
  if (integrator == "backwardEuler" || integrator == "asyncStable") options.emplace_back("implicitContact");
  if (integrator == "asyncStable" || integrator == "asyncPaper") {
    if (nonlinear) options.emplace_back("noLaggedSchur");  // "plain" has laggedSchur on, the default
    options.emplace_back("substepStatePrediction");
    options.emplace_back("proposedRegions");
  }
  if (integrator == "asyncStable") {
    options.emplace_back("quickSetUp");
    options.emplace_back("schedule");
  }
  if (integrator == "asyncNested") options.emplace_back("schedule");  // run-time regions that nest
  return options;
}

std::vector<MatrixCase> allCases() {
  std::vector<MatrixCase> cases;
  for (const std::string& integrator : integrators) {
    for (const std::string& model : models) {
      for (const std::string& option : optionsFor(integrator, model)) {
        for (const bool kill9 : {false, true}) cases.push_back({integrator, model, option, kill9});
      }
    }
  }
  return cases;
}

/// Every integrator twice (once per way of stopping), then one more case for each force
/// model and option not drawn yet: 14 to 20 cases, drawn from the seed.
std::vector<MatrixCase> seededCases() {
  std::vector<MatrixCase> all = allCases();
  std::mt19937_64 random(matrixSeed());
  std::shuffle(all.begin(), all.end(), random);
  std::vector<MatrixCase> chosen;
  std::set<std::string> taken, models, options;
  const auto take = [&](const MatrixCase& c) {
    if (!taken.insert(c.name()).second) return;
    chosen.push_back(c);
    models.insert(c.model);
    options.insert(c.option);
  };
  for (const std::string& integrator : integrators) {
    for (const bool kill9 : {false, true}) {
      const auto it = std::find_if(all.begin(), all.end(),
                                   [&](const MatrixCase& c) { return c.integrator == integrator && c.kill9 == kill9; });
      take(*it);
    }
  }
  for (const MatrixCase& c : all) {
    if (models.count(c.model) == 0 || options.count(c.option) == 0) take(c);
  }
  return chosen;
}

/// A 3 x 1 x 1 bar of 6 x 2 x 2 cells (63 vertices, 120 tetrahedra), fixed at x = 0 and
/// pulled down at x = 3 for 0.15 s (the tip moves about a quarter of the bar's height, far
/// enough for the nonlinear models to differ from the linear one), 20 frames per second.
nlohmann::json sceneFor(const MatrixCase& c) {
  nlohmann::json scene = nlohmann::json::parse(R"({
    "mesh": {"generator": "box", "size": [3, 1, 1], "cells": [6, 2, 2],
             "material": {"density": 1000, "youngsModulus": 1e6, "poissonRatio": 0.4}},
    "fixed": {"sets": ["xmin"]},
    "forces": [{"type": "pull", "set": "xmax", "force": [0, -8000, 0], "window": [0, 0.15]}],
    "frames": {"rate": 20, "count": 100000},
    "output": {"file": "out.afsim", "velocities": true}
  })");
  static const std::map<std::string, std::string> modelTypes = {{"linear", "linear"},
                                                                {"corotational", "corotational"},
                                                                {"stvk", "stvk"},
                                                                {"neoHookean", "neo-hookean"},
                                                                {"mooneyRivlin", "mooney-rivlin"}};
  scene["forceModel"] = {{"type", modelTypes.at(c.model)}};
  if (c.model == "mooneyRivlin") {
    // Shear modulus 2 (mu01 + mu10) = 3.6e5, as E = 1e6 and nu = 0.4 give the others.
    scene["forceModel"]["mooneyRivlin"] = {{"mu01", 3e4}, {"mu10", 1.5e5}, {"v1", 1e6}};
  }
  const bool explicitMethod = c.integrator == "centralDifferences" || c.integrator == "symplecticEuler";
  nlohmann::json options = nlohmann::json::object();
  const bool nonlinear = c.model != "linear";
  if (c.integrator == "backwardEuler" && nonlinear && c.option != "reuseFactor") options["maxIterations"] = 3;
  if (c.option == "lineSearch") options["lineSearch"] = true;
  if (c.option == "reuseFactor") {
    options["reuseFactor"] = true;
    options["pcgTolerance"] = 1e-10;
  }
  if (c.option == "exactSolves") options["reuseFactor"] = false;
  if (isAsync(c.integrator) || c.integrator == "multirateUncoupled" || c.integrator == "schroeder2011") {
    options["regions"] = {{{"name", "tip"}, {"ratio", 4}, {"vertexSets", {"xmax"}}}};
  }
  const nlohmann::json nextToTip = nlohmann::json::parse(R"([{"min": [2.4, -1, -1], "max": [2.6, 2, 2]}])");
  if (c.integrator == "asyncNested") {
    // The tip at 8 and the layer beside it at 4 share elements: the hierarchy solve.
    options["regions"] = {{{"name", "tip"}, {"ratio", 8}, {"vertexSets", {"xmax"}}},
                          {{"name", "beside"}, {"ratio", 4}, {"boxes", nextToTip}}};
  }
  if (c.option == "schedule") {
    // Windows at 0.12-0.37 s (frames 3-7 at 20 per second): the resumed run picks them up
    // from the time alone. Nested: the tip at 8 inside a longer window of its neighbour at 4.
    nlohmann::json schedule = {
        {{"name", "tip"}, {"ratio", 8}, {"vertexSets", {"xmax"}}, {"start", 0.12}, {"end", 0.37}}};
    if (c.integrator == "asyncNested") {
      schedule.push_back({{"name", "beside"}, {"ratio", 4}, {"boxes", nextToTip}, {"start", 0.07}, {"end", 0.42}});
    }
    options["regions"] = {{"adaptive", {{"schedule", schedule}, {"nest", c.integrator == "asyncNested"}}}};
  }
  if (c.option == "quickSetUp") options["quickSetUp"] = true;
  if (c.option == "proposedRegions") options["regions"] = "auto";
  if (c.integrator == "asyncPaper") options["coupling"] = "paper";
  if (c.option == "noLaggedSchur") options["laggedSchur"] = false;
  if (c.option == "substepStatePrediction") options["substepStatePrediction"] = true;
  static const std::map<std::string, std::string> names = {{"backwardEuler", "backward-euler"},
                                                           {"trapezoidal", "trapezoidal"},
                                                           {"centralDifferences", "central-differences"},
                                                           {"symplecticEuler", "symplectic-euler"},
                                                           {"asyncStable", "async"},
                                                           {"asyncPaper", "async"},
                                                           {"multirateUncoupled", "multirate-uncoupled"},
                                                           {"schroeder2011", "schroeder2011"},
                                                           {"asyncNested", "async"}};
  scene["integrator"] = {
      {"name", names.at(c.integrator)}, {"stepsPerFrame", explicitMethod ? 100 : 5}, {"options", options}};
  if (c.option == "contact" || c.option == "substepStatePrediction" || c.option == "implicitContact") {
    // The bar sags onto a ground just below it and rubs on it (friction keeps v in the force).
    scene["gravity"] = {0, -9.81, 0};
    scene["contact"] = {
        {"ground", {{"height", -0.15}, {"up", {0, 1, 0}}}}, {"stiffness", 2e5}, {"damping", 50}, {"friction", 0.3}};
    if (c.option == "implicitContact") {
      scene["contact"]["implicit"] = true;  // frictionless
      scene["contact"].erase("friction");
    }
  }
  return scene;
}

/// Whether a case's resumed run may differ from the uninterrupted one, and why: the state
/// that no checkpoint holds, as the test knows it from the case (never from the
/// simulator's own summary). Empty: bit for bit.
std::string inexactBecause(const MatrixCase& c) {
  const bool nonlinear = c.model != "linear";
  if (c.option == "implicitContact" && c.integrator == "asyncStable") return "implicit contact's blocks in A^S";
  if (c.option == "quickSetUp") return "whether the partition still solves on the whole system's factor";
  // The two-level solve keeps H^{LL*}'s factor across large steps for nonlinear forces; the
  // hierarchy solve (fixed nested regions) refactors every large step, but a nested
  // schedule runs the two-level solve outside its windows.
  const bool twoLevel = c.integrator == "asyncStable" || c.integrator == "asyncPaper" ||
                        (c.integrator == "asyncNested" && c.option == "schedule");
  if (twoLevel && nonlinear && c.option != "noLaggedSchur") return "the lagged Schur factor (laggedSchur, the default)";
  return "";
}

/// The bound for a resume the test knows to be inexact (inexactBecause): the kept factors it cannot
/// restore are preconditioners of iterations run to a relative residual of 1e-10
/// (pcgTolerance here, laggedSchur's fixed tolerance), so each frame after the resume
/// differs from the uninterrupted run by about that much relative to the motion; over the
/// few frames compared, 1e-6 of the largest |u| (and |v|) leaves room for growth and still
/// catches any state that was really lost (those differ by percents).
constexpr double caveatBound = 1e-6;

class ResumeMatrixTest : public asyncfem::test::ResumeHarness, public ::testing::WithParamInterface<MatrixCase> {
 protected:
  /// Starts the simulator with `arguments`, output to files named by `tag`.
  Child start(const std::vector<std::string>& arguments, const std::string& tag) const {
    std::vector<std::string> command{simulatorPath};
    command.insert(command.end(), arguments.begin(), arguments.end());
    return startCommand(command, tag);
  }

  /// Runs the simulator to its end; its exit status (-1 if it did not exit normally).
  int runToEnd(const std::vector<std::string>& arguments, const std::string& tag) const {
    std::vector<std::string> command{simulatorPath};
    command.insert(command.end(), arguments.begin(), arguments.end());
    return runCommandToEnd(command, tag);
  }
};

TEST_P(ResumeMatrixTest, ResumedRunMatchesAnUninterruptedOne) {
  const MatrixCase& c = GetParam();
  const std::uint64_t seed = matrixSeed();
  std::mt19937_64 random(seed ^ stableHash(c.name()));
  const int stopAfter = std::uniform_int_distribution<int>(1, 6)(random);
  std::cout << "resume matrix: seed " << seed << " (ASYNCFEM_RESUME_MATRIX_SEED), " << c.name()
            << ": interrupted once frame " << stopAfter << " is on disk\n";
  const fs::path scene = folder_ / "scene.json";
  std::ofstream(scene) << sceneFor(c).dump(2);
  const fs::path output = folder_ / "out.afsim";

  // The interrupted run: checkpoints every 3 frames, so SIGKILL makes the resume recompute.
  Child child = start({scene.string(), "--quiet", "--checkpoint-every", "3"}, "interrupted");
  const bool reached = waitForFrames(output, stopAfter, child);
  ::kill(child.pid, c.kill9 ? SIGKILL : SIGINT);
  finish(child, 60.0);
  ASSERT_TRUE(reached) << "frame " << stopAfter << " never appeared: " << printed("interrupted", "err");
  if (c.kill9) {
    ASSERT_TRUE(WIFSIGNALED(child.status)) << "the run ended before it was killed";
  } else {
    ASSERT_TRUE(WIFEXITED(child.status)) << "SIGINT was not handled";
    ASSERT_EQ(WEXITSTATUS(child.status), 128 + SIGINT) << printed("interrupted", "err");
  }
  const auto [onDisk, checkpointed] = asyncfem::test::checkLeftBehind(output, stopAfter, c.kill9);
  const std::int64_t frames = onDisk + 3;

  const std::string count = std::to_string(frames);
  ASSERT_EQ(runToEnd({scene.string(), "--resume", "--frames", count, "--checkpoint-every", "3"}, "resumed"), 0)
      << printed("resumed", "err");
  const fs::path reference = folder_ / "reference.afsim";
  ASSERT_EQ(runToEnd({scene.string(), "--quiet", "--frames", count, "--output", reference.string()}, "reference"), 0)
      << printed("reference", "err");

  const std::string resumedOut = printed("resumed", "out");
  const std::size_t caveat = resumedOut.find("resume: ");
  const std::string inexact = inexactBecause(c);
  const Difference d = compareFrames(output, reference, frames);
  std::cout << "  interrupted after frame " << onDisk << " (checkpoint " << checkpointed << "), compared " << frames
            << " frames: max |du| " << d.displacement << " of max |u| " << d.largestDisplacement << ", max |dv| "
            << d.velocity << (inexact.empty() ? ", expected bit for bit" : ", expected within the bound: " + inexact)
            << "\n";
  ASSERT_GT(d.largestDisplacement, 1e-3) << "the bar did not move";
  EXPECT_TRUE(d.sameTimes);
  if (inexact.empty()) {
    // Nothing a checkpoint lacks: bit for bit, every byte of the file, whatever the run said.
    EXPECT_TRUE(readText(output) == readText(reference))
        << "the resumed run differs from the uninterrupted one: max |du| = " << d.displacement
        << ", max |dv| = " << d.velocity;
  } else {
    // The simulator must have said so before resuming (before its summary, so before any
    // frame), and the difference stays within the bound.
    ASSERT_NE(caveat, std::string::npos) << "a resume that cannot be exact (" << inexact << ") was not announced";
    EXPECT_LT(caveat, resumedOut.find("offlineSimulator: ")) << resumedOut;
    EXPECT_LE(d.displacement, caveatBound * d.largestDisplacement) << resumedOut;
    EXPECT_LE(d.velocity, caveatBound * d.largestVelocity) << resumedOut;
  }
}

std::string caseName(const ::testing::TestParamInfo<MatrixCase>& info) { return info.param.name(); }

INSTANTIATE_TEST_SUITE_P(Seeded, ResumeMatrixTest, ::testing::ValuesIn(seededCases()), caseName);
INSTANTIATE_TEST_SUITE_P(Full, ResumeMatrixTest, ::testing::ValuesIn(allCases()), caseName);

}  // namespace
