// SPDX-License-Identifier: BSD-3-Clause
// The resume matrix on the PETSc backend (docs/robustness.md, "The resume matrix";
// docs/petsc-backend.md, "Checkpoints and --resume"): backward Euler and the asynchronous
// integrator run by `mpiexec -n N offlineSimulator --backend petsc` on 1 and 2 ranks, one
// rank stopped by SIGINT (every rank stops after the same frame) or killed with SIGKILL
// (mpiexec ends the others) at a frame drawn from a seeded generator, then resumed with
// --resume on the same number of ranks and compared with an uninterrupted run on those
// ranks. The oracle comes from the case (oracleFor): byte for byte where the run is
// deterministic, else a stated bound on the difference from the uninterrupted run.
// ctest runs the instantiation "Petsc" (5 cases: every integrator on 1 and 2 ranks, both
// ways of stopping, both solvers); all 10 with
//   build/bin/resumeMatrixPetscTests --gtest_filter='PetscFull/*'
// ASYNCFEM_RESUME_MATRIX_SEED=N draws other interruption frames.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "resumeHarness.hpp"

namespace {

namespace fs = std::filesystem;
using asyncfem::test::Child;
using asyncfem::test::matrixSeed;
using asyncfem::test::readText;
using asyncfem::test::stableHash;

const std::string simulatorPath = std::string(ASYNCFEM_BIN_DIR) + "/offlineSimulator";

/// One case: integrator, number of ranks, PETSc solver, how the run is stopped.
struct PetscCase {
  std::string integrator;  ///< backwardEuler, async
  int ranks = 1;
  std::string solver;  ///< mumps (direct), cg-gamg (the backend's default: CG with GAMG to 1e-10)
  bool kill9 = false;  ///< SIGKILL instead of SIGINT

  std::string name() const {
    std::string solverName = solver == "mumps" ? "mumps" : "cgGamg";
    return integrator + "_np" + std::to_string(ranks) + "_" + solverName + (kill9 ? "_kill9" : "_sigint");
  }
};

void PrintTo(const PetscCase& c, std::ostream* out) { *out << c.name(); }

/// Both integrators on 1 and 2 ranks with MUMPS, each stopped both ways; the default
/// iterative solver on 2 ranks, stopped by SIGINT: 10 cases.
std::vector<PetscCase> allPetscCases() {
  std::vector<PetscCase> cases;
  for (const std::string integrator : {"backwardEuler", "async"}) {
    for (const int ranks : {1, 2}) {
      for (const bool kill9 : {false, true}) cases.push_back({integrator, ranks, "mumps", kill9});
    }
    cases.push_back({integrator, 2, "cg-gamg", false});
  }
  return cases;
}

/// What ctest runs: each integrator on 1 and on 2 ranks, stopped one way on 1 rank and the
/// other on 2 (backward Euler SIGINT on 1 rank, the asynchronous integrator SIGKILL), and
/// CG + GAMG with the asynchronous integrator: 5 cases.
std::vector<PetscCase> ctestPetscCases() {
  std::vector<PetscCase> cases;
  for (const PetscCase& c : allPetscCases()) {
    const bool killedOnOneRank = c.integrator == "async";
    const bool mumpsPick = c.solver == "mumps" && c.kill9 == (killedOnOneRank == (c.ranks == 1));
    if (mumpsPick || (c.solver != "mumps" && c.integrator == "async")) cases.push_back(c);
  }
  return cases;
}

/// The bound on max |du| / max |u| (and |dv| / |v|) a case's resumed run is held to, and
/// why it is not zero; zero: every byte of the file equals the uninterrupted run's.
struct Oracle {
  double bound = 0.0;
  std::string reason;
};

Oracle oracleFor(const PetscCase& c) {
  if (c.solver != "mumps") {
    // CG stops at a relative residual of 1e-10 and starts from the previous step's
    // increment, which a checkpoint does not hold (the first solve after the resume starts
    // from zero): each step's solution may differ by kappa 1e-10 (kappa ~ 1e3 for this
    // bar's M + h^2 K), and the motion carries it over the few frames compared.
    return {1e-6, "CG's tolerance, restarted from a zero initial guess after the resume"};
  }
  if (c.ranks > 1) {
    // PETSc adds the matrix and vector entries that other ranks send in the order the
    // messages arrive, so even two uninterrupted runs differ in the last bits (observed
    // 3e-16 of max |u|); MUMPS solves directly, so the difference stays round-off amplified
    // by the condition number (~1e3) over a few frames of 5 steps. A lost or misread state
    // (v, the time, a frame) differs by percents.
    return {1e-10, "the order in which PETSc sums entries sent by other ranks"};
  }
  return {};
}

constexpr int kStepsPerFrame = 5;

/// A 2 x 0.5 x 0.5 box of 8 x 2 x 2 cells (81 vertices), fixed at x = 0, under gravity
/// and pulled down at x = 2 for 0.2 s, linear FEM, 20 frames per second of 5 steps; the
/// asynchronous integrator steps the free end at ratio 4.
nlohmann::json petscScene(const PetscCase& c) {
  nlohmann::json scene = nlohmann::json::parse(R"({
    "mesh": {"generator": "box", "size": [2, 0.5, 0.5], "cells": [8, 2, 2]},
    "fixed": {"sets": ["xmin"]},
    "forces": [{"type": "pull", "set": "xmax", "force": [0, -50, 0], "window": [0, 0.2]}],
    "gravity": [0, -9.81, 0],
    "forceModel": {"type": "linear"},
    "frames": {"rate": 20, "count": 100000},
    "output": {"velocities": true}
  })");
  nlohmann::json integrator = {{"stepsPerFrame", kStepsPerFrame}};
  if (c.integrator == "async") {
    integrator["name"] = "async";
    integrator["options"] = {{"regions", {{{"name", "end"}, {"ratio", 4}, {"vertexSets", {"xmax"}}}}}};
  } else {
    integrator["name"] = "backward-euler";
  }
  scene["integrator"] = integrator;
  return scene;
}

/// The processes whose parent is `parent` and whose name starts with offlineSimulator
/// (the ranks mpiexec started), by ascending id.
std::vector<pid_t> ranksOf(pid_t parent) {
  std::vector<pid_t> out;
  for (const fs::directory_entry& entry : fs::directory_iterator("/proc")) {
    const std::string id = entry.path().filename().string();
    if (id.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(entry.path() / "stat");
    std::string line;
    std::getline(stat, line);
    // "pid (name) state ppid ...": the name may hold spaces, so read after the last ')'.
    const std::size_t open = line.find('('), close = line.rfind(')');
    if (open == std::string::npos || close == std::string::npos || close + 2 > line.size()) continue;
    std::istringstream rest(line.substr(close + 2));
    char state = 0;
    pid_t parentId = -1;
    rest >> state >> parentId;
    if (parentId == parent && line.compare(open + 1, 14, "offlineSimulat") == 0) out.push_back(std::stoi(id));
  }
  std::sort(out.begin(), out.end());
  return out;
}

class ResumeMatrixPetscTest : public asyncfem::test::ResumeHarness, public ::testing::WithParamInterface<PetscCase> {
 protected:
  void SetUp() override {
    ResumeHarness::SetUp();
    // Open MPI refuses to run as root and to start more ranks than cores unless told
    // (other MPI implementations ignore these); a value the caller set is kept.
    ::setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 0);
    ::setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 0);
    ::setenv("OMPI_MCA_rmaps_base_oversubscribe", "1", 0);
    ::setenv("OMPI_MCA_btl_vader_single_copy_mechanism", "none", 0);
  }

  /// mpiexec -n ranks offlineSimulator scene --backend petsc --petsc-solver S arguments...
  std::vector<std::string> command(const PetscCase& c, const std::vector<std::string>& arguments) const {
    std::vector<std::string> out = {
        ASYNCFEM_MPIEXEC, "-n",    std::to_string(c.ranks), simulatorPath, (folder_ / "scene.json").string(),
        "--backend",      "petsc", "--petsc-solver",        c.solver};
    out.insert(out.end(), arguments.begin(), arguments.end());
    return out;
  }
};

TEST_P(ResumeMatrixPetscTest, ResumedRunMatchesAnUninterruptedOne) {
  const PetscCase& c = GetParam();
  std::mt19937_64 random(matrixSeed() ^ stableHash(c.name()));
  const int stopAfter = std::uniform_int_distribution<int>(1, 4)(random);
  std::cout << "PETSc resume matrix: " << c.name() << ", interrupted once frame " << stopAfter << " is on disk\n";
  std::ofstream(folder_ / "scene.json") << petscScene(c).dump(2);
  const fs::path output = folder_ / "out.afsim";

  // The interrupted run: checkpoints every 3 frames, so SIGKILL makes the resume recompute.
  Child launcher = startCommand(command(c, {"--quiet", "--checkpoint-every", "3", "-o", output.string()}), "stopped");
  const bool reached = waitForFrames(output, stopAfter, launcher);
  const std::vector<pid_t> ranks = ranksOf(launcher.pid);
  if (!ranks.empty()) ::kill(ranks.back(), c.kill9 ? SIGKILL : SIGINT);
  finish(launcher, 60.0);
  ASSERT_TRUE(reached) << "frame " << stopAfter << " never appeared: " << printed("stopped", "err");
  ASSERT_EQ(ranks.size(), static_cast<std::size_t>(c.ranks)) << "mpiexec's ranks were not found";
  ASSERT_TRUE(WIFEXITED(launcher.status)) << "mpiexec did not exit";
  if (c.kill9) {
    EXPECT_NE(WEXITSTATUS(launcher.status), 0) << "the run ended normally although a rank was killed";
  } else {
    EXPECT_EQ(WEXITSTATUS(launcher.status), 128 + SIGINT) << printed("stopped", "err");
  }
  const auto [onDisk, checkpointed] = asyncfem::test::checkLeftBehind(output, stopAfter, c.kill9);
  const std::int64_t frames = onDisk + 3;
  const std::string count = std::to_string(frames);

  ASSERT_EQ(
      runCommandToEnd(command(c, {"--resume", "--frames", count, "--checkpoint-every", "3", "-o", output.string()}),
                      "resumed"),
      0)
      << printed("resumed", "err");
  // The resumed run continued from the checkpoint: its summary counts only the steps after it.
  const std::string summary = printed("resumed", "out");
  std::smatch counted;
  ASSERT_TRUE(std::regex_search(summary, counted, std::regex(R"(, (\d+) steps of h)"))) << summary;
  EXPECT_EQ(std::stoll(counted[1].str()), (frames - checkpointed) * kStepsPerFrame) << summary;
  const fs::path reference = folder_ / "reference.afsim";
  ASSERT_EQ(runCommandToEnd(command(c, {"--quiet", "--frames", count, "-o", reference.string()}), "reference"), 0)
      << printed("reference", "err");

  const Oracle oracle = oracleFor(c);
  const asyncfem::test::Difference d = asyncfem::test::compareFrames(output, reference, frames);
  std::cout << "  interrupted after frame " << onDisk << " (checkpoint " << checkpointed << "), compared " << frames
            << " frames: max |du| " << d.displacement << " of max |u| " << d.largestDisplacement << ", max |dv| "
            << d.velocity << " of max |v| " << d.largestVelocity << ", expected ";
  if (oracle.reason.empty()) {
    std::cout << "bit for bit\n";
  } else {
    std::cout << "within " << oracle.bound << " of the largest: " << oracle.reason << "\n";
  }
  ASSERT_GT(d.largestDisplacement, 1e-3) << "the bar did not move";
  EXPECT_EQ(asyncfem::SimulationReader(output).numFrames(), frames);
  EXPECT_TRUE(d.sameTimes);
  if (oracle.reason.empty()) {
    EXPECT_TRUE(readText(output) == readText(reference))
        << "the resumed run differs from the uninterrupted one: max |du| = " << d.displacement
        << ", max |dv| = " << d.velocity;
  } else {
    EXPECT_LE(d.displacement, oracle.bound * d.largestDisplacement);
    EXPECT_LE(d.velocity, oracle.bound * d.largestVelocity);
  }
}

std::string caseName(const ::testing::TestParamInfo<PetscCase>& info) { return info.param.name(); }

INSTANTIATE_TEST_SUITE_P(Petsc, ResumeMatrixPetscTest, ::testing::ValuesIn(ctestPetscCases()), caseName);
INSTANTIATE_TEST_SUITE_P(PetscFull, ResumeMatrixPetscTest, ::testing::ValuesIn(allPetscCases()), caseName);

}  // namespace
