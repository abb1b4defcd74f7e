// SPDX-License-Identifier: BSD-3-Clause
// The stability stress test's pieces (benchmarkTools/stabilityStress.hpp): the mesh
// perturber, the verdict, the grid and its runner.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <asyncfem/benchmarkTools/stabilityStress.hpp>
#include <asyncfem/core/error.hpp>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace asyncfem;

const Eigen::Vector3i kCells(4, 2, 2);

// Signed volume of element e at positions (an independent oracle for the perturber's check).
double signedVolume(const TetMesh& mesh, const Eigen::Matrix3Xd& positions, int e) {
  const Eigen::Vector4i t = mesh.element(e);
  const Eigen::Vector3d a = positions.col(t[0]);
  return (positions.col(t[1]) - a).cross(positions.col(t[2]) - a).dot(positions.col(t[3]) - a) / 6.0;
}

TEST(StabilityStress, PerturbedMeshHasNoInvertedElement) {
  const BoxMeshSpec spec = stressBarSpec(kCells, 100.0);
  const TetMesh regular = makeBoxMesh(spec);
  const PerturbedMesh perturbed = perturbedBoxMesh(spec, 7);
  ASSERT_EQ(perturbed.mesh.numElements(), regular.numElements());
  double worst = 1e300;
  for (int e = 0; e < regular.numElements(); ++e) {
    const double before = signedVolume(regular, regular.restPositions(), e);
    const double after = signedVolume(regular, perturbed.mesh.restPositions(), e);
    EXPECT_GT(before * after, 0.0) << "element " << e << " inverted or flat";
    double longest = 0.0;
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) {
        const Eigen::Vector4i t = regular.element(e);
        longest = std::max(
            longest, (perturbed.mesh.restPositions().col(t[i]) - perturbed.mesh.restPositions().col(t[j])).norm());
      }
    }
    worst = std::min(worst, 6.0 * std::sqrt(2.0) * std::abs(after) / std::pow(longest, 3));
  }
  // The reported quality is this minimum (same formula, same order of operations up to
  // round-off: 1e-12 relative is far above it).
  EXPECT_NEAR(perturbed.worstQuality, worst, 1e-12 * worst);
  EXPECT_GT(perturbed.worstQuality, 1e-3);
  EXPECT_LT(perturbed.worstQuality, 1.0);  // it did distort something
  // Sets survive, so scenes naming them still work.
  EXPECT_EQ(perturbed.mesh.vertexSet("xmin"), regular.vertexSet("xmin"));
  EXPECT_EQ(perturbed.mesh.elementSets().size(), regular.elementSets().size());
}

TEST(StabilityStress, PerturbedVerticesMoveAtMostTheStatedShift) {
  const BoxMeshSpec spec = stressBarSpec(kCells, 1.0);
  const Eigen::Matrix3Xd rest = makeBoxMesh(spec).restPositions();
  const double maxShiftCells = 0.25;
  const Eigen::Matrix3Xd moved = perturbedBoxMesh(spec, 3, maxShiftCells).mesh.restPositions();
  const Eigen::Vector3d cell = spec.size.cwiseQuotient(spec.cells.cast<double>());
  double largest = 0.0;
  for (int v = 0; v < rest.cols(); ++v) {
    for (int c = 0; c < 3; ++c) {
      const double shift = std::abs(moved(c, v) - rest(c, v));
      // x + s - x differs from s by an ulp of x (|x| <= 1): 1e-12 of a cell is far above it.
      EXPECT_LE(shift, maxShiftCells * cell[c] * (1.0 + 1e-12)) << "vertex " << v << " axis " << c;
      const bool onFace = std::abs(rest(c, v)) < 1e-12 || std::abs(rest(c, v) - spec.size[c]) < 1e-12;
      if (onFace) {
        EXPECT_EQ(moved(c, v), rest(c, v)) << "vertex " << v << " left the face along axis " << c;
      }
      largest = std::max(largest, shift / cell[c]);
    }
  }
  // Uniform shifts of some hundred coordinates: the largest is near the bound, not 0.
  EXPECT_GT(largest, 0.5 * maxShiftCells);
}

TEST(StabilityStress, PerturbationIsDeterministicForASeed) {
  const BoxMeshSpec spec = stressBarSpec(kCells, 1.0);
  const Eigen::Matrix3Xd first = perturbedBoxMesh(spec, 11).mesh.restPositions();
  EXPECT_EQ(perturbedBoxMesh(spec, 11).mesh.restPositions(), first);
  EXPECT_NE(perturbedBoxMesh(spec, 12).mesh.restPositions(), first);
}

// Shifts of three cells fold elements over in every draw: the perturber refuses them
// instead of returning an inverted mesh (its inversion check is live).
TEST(StabilityStress, PerturberRefusesShiftsThatInvert) {
  try {
    (void)perturbedBoxMesh(stressBarSpec(kCells, 1.0), 1, 3.0);
    FAIL() << "expected an error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("without inverting or flattening an element"), std::string::npos)
        << error.what();
  }
}

TEST(StabilityStress, VerdictClassifiesOutcomes) {
  StressOutcome outcome;
  outcome.energyMeasured = true;
  outcome.energyGrowth = 0.5;
  EXPECT_EQ(stabilityVerdict(outcome), StabilityVerdict::stable);
  outcome.energyGrowth = 1.0 + 0.5 * energyGrowthTolerance;  // round-off, not growth
  EXPECT_EQ(stabilityVerdict(outcome), StabilityVerdict::stable);
  outcome.energyGrowth = 1.0 + 2.0 * energyGrowthTolerance;
  EXPECT_EQ(stabilityVerdict(outcome), StabilityVerdict::energyGrowth);
  outcome.energyMeasured = false;  // the loads never ended: a growth is not a verdict
  EXPECT_EQ(stabilityVerdict(outcome), StabilityVerdict::stable);
  outcome.failedFrame = 3;  // a refused frame outranks everything
  EXPECT_EQ(stabilityVerdict(outcome), StabilityVerdict::blowUp);
  outcome.failedFrame = 0;
  outcome.energyGrowth = 0.0;
  EXPECT_EQ(stabilityVerdict(outcome), StabilityVerdict::blowUp);
  EXPECT_EQ(toString(StabilityVerdict::blowUp), "blow-up");
  EXPECT_EQ(toString(StabilityVerdict::energyGrowth), "energy growth");
}

TEST(StabilityStress, GridSelectionNarrowsTheLists) {
  const StressGrid whole = stressGrid({});
  EXPECT_EQ(whole.stiffnessRatios, (std::vector<double>{1, 1e2, 1e4, 1e6}));
  EXPECT_EQ(whole.ratios, (std::vector<int>{1, 8, 50, 200}));
  EXPECT_EQ(whole.dampings.size(), 3U);
  EXPECT_EQ(whole.integrators.size(), 4U);
  EXPECT_EQ(whole.meshes, (std::vector<bool>{false, true}));
  StressGridSelection selection;
  selection.full = true;
  selection.integrators = {"async-symmetric"};
  selection.dampings = {"heavy"};
  selection.meshes = {"perturbed"};
  const StressGrid narrowed = stressGrid(selection);
  EXPECT_EQ(narrowed.stiffnessRatios.size(), 7U);
  EXPECT_EQ(narrowed.ratios, (std::vector<int>{1, 2, 8, 32, 100, 200}));
  ASSERT_EQ(narrowed.integrators.size(), 1U);
  EXPECT_EQ(narrowed.integrators[0], (std::pair<std::string, std::string>{"async", "symmetric"}));
  ASSERT_EQ(narrowed.dampings.size(), 1U);
  EXPECT_EQ(narrowed.dampings[0].alpha, 5.0);
  EXPECT_EQ(narrowed.meshes, std::vector<bool>{true});
}

// Runs finish out of order on three threads; reports still come 0, 1, 2, ..., and a run
// that throws is reported as failed at frame 0.
TEST(StabilityStress, RunsAreReportedInOrder) {
  const std::size_t count = 6;
  std::vector<std::size_t> order;
  std::vector<StressOutcome> reported(count);
  runStressJobsInOrder(
      count, 3,
      [&](std::size_t index) {
        std::this_thread::sleep_for(std::chrono::milliseconds(5 * (count - index)));
        if (index == 4) throw std::runtime_error("no mesh");
        StressOutcome outcome;
        outcome.maxDisplacement = static_cast<double>(index);
        return outcome;
      },
      [&](std::size_t index, const StressOutcome& outcome) {
        order.push_back(index);
        reported[index] = outcome;
      });
  EXPECT_EQ(order, (std::vector<std::size_t>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(reported[5].maxDisplacement, 5.0);
  EXPECT_EQ(reported[4].failedFrame, 0);
  EXPECT_EQ(reported[4].failure, "setup failed: no mesh");
  EXPECT_EQ(stabilityVerdict(reported[4]), StabilityVerdict::blowUp);
}

// A tiny grid end to end: the bar at stiffness ratio 1 with the fast region at m = 50,
// undamped, on the perturbed 8x2x2 mesh of seed 1 (docs/benchmarks.md,
// stabilityStressTest). Backward Euler and async keep the energy at or below E_0;
// multirate-uncoupled, the comparator without coupling, blows up there (at frame 20 with
// one thread), and the runner and the verdict must say so (the negative control).
TEST(StabilityStress, TinyGridSeparatesStableFromUnstable) {
  const std::filesystem::path folder =
      std::filesystem::temp_directory_path() / ("asyncfem-stress-test-" + std::to_string(::getpid()));
  std::filesystem::create_directories(folder);
  StressGridSelection selection;
  selection.stiffnessRatios = {1.0};
  selection.ratios = {50};
  selection.dampings = {"none"};
  selection.integrators = {"async", "multirate-uncoupled", "backward-euler"};
  selection.meshes = {"perturbed"};
  const std::vector<StressJob> jobs = stressJobs(stressGrid(selection), Eigen::Vector3i(8, 2, 2), 1, folder);
  ASSERT_EQ(jobs.size(), 3U);
  EXPECT_TRUE(std::filesystem::exists(jobs[0].meshFile));
  EXPECT_LT(jobs[0].quality, 1.0);
  const int frames = 25;
  for (const StressJob& job : jobs) {
    const StressOutcome outcome = runStressJob(job, frames);
    const std::string& integrator = job.stressCase.integrator;
    if (integrator == "multirate-uncoupled") {
      EXPECT_EQ(stabilityVerdict(outcome), StabilityVerdict::blowUp) << "max E/E0 " << outcome.energyGrowth;
      EXPECT_GE(outcome.failedFrame, 0);
      EXPECT_LT(outcome.failedFrame, frames);
    } else {
      EXPECT_EQ(stabilityVerdict(outcome), StabilityVerdict::stable) << integrator << ": " << outcome.failure;
      EXPECT_TRUE(outcome.energyMeasured);
      EXPECT_GT(outcome.energyGrowth, 0.0);
      // The bar starts bent by 0.02 at its tip and only loses energy: |u| stays of that size.
      EXPECT_GT(outcome.maxDisplacement, 0.0);
      EXPECT_LT(outcome.maxDisplacement, 0.05) << integrator;
    }
  }
  std::filesystem::remove_all(folder);
}

}  // namespace
