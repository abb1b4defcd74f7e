// SPDX-License-Identifier: BSD-3-Clause
// Running benchmark configurations, the reference they are measured against and the
// vertex groups of their errors, on a small two-material bar.
#include <gtest/gtest.h>

#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/benchmarkTools/benchmarkReference.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/asyncScene.hpp>
#include <nlohmann/json.hpp>
#include <string>

namespace asyncfem {
namespace {

// An 8 x 2 x 2-cell bar fixed at x = 0 whose last quarter is 50 times stiffer and 5 times
// lighter, released from rest under gravity; "async" with the given options at hL = 0.1 s,
// 10 frames per s.
Scene barScene(const nlohmann::json& asyncOptions) {
  const nlohmann::json json = nlohmann::json::parse(R"({
    "mesh": {"generator": "box", "size": [1, 0.25, 0.25], "cells": [8, 2, 2],
             "material": {"density": 1000, "youngsModulus": 1e5, "poissonRatio": 0.4},
             "regions": [{"name": "tip", "min": [0.75, -1, -1], "max": [2, 2, 2],
                          "material": {"density": 200, "youngsModulus": 5e6, "poissonRatio": 0.3}}]},
    "fixed": {"sets": ["xmin"]},
    "gravity": [0, -9.81, 0],
    "integrator": {"name": "async", "timestep": 0.1},
    "frames": {"rate": 10, "count": 3}
  })");
  Scene scene = parseScene(json, ".", "bar.json");
  scene.integrator.options = asyncOptions;
  return scene;
}

const nlohmann::json kExplicitRegions = {{"regions", {{{"name", "tip"}, {"ratio", 4}, {"elementSets", {"tip"}}}}}};

Simulation baselineOf(const Scene& scene) {
  BenchmarkConfiguration single;
  single.stepsPerFrame = 1;
  return buildSimulation(configuredScene(scene, single, 1));
}

BenchmarkConfiguration configuration(const std::string& integrator, int stepsPerFrame,
                                     const nlohmann::json& options = nlohmann::json::object()) {
  BenchmarkConfiguration c;
  c.integrator = integrator;
  c.stepsPerFrame = stepsPerFrame;
  c.options = options;
  return c;
}

TEST(BenchmarkRun, RunsAConfigurationAndRecordsItsRatios) {
  const Scene scene = barScene(kExplicitRegions);
  const BenchmarkRun run = runConfiguration(scene, configuration("async", 2, kExplicitRegions), 3, 2);
  EXPECT_TRUE(run.completed);
  EXPECT_EQ(run.frames.size(), 3u);
  EXPECT_EQ(run.secondsPerFrame.size(), 2u);  // one per repeat
  EXPECT_EQ(run.stepsPerFrame, 2);
  EXPECT_EQ(run.ratios, std::vector<int>{4});
  EXPECT_GT(run.solvesPerFrame, 0.0);
  EXPECT_GT(run.frames.back().norm(), 0.0);
  const BenchmarkRun single = runConfiguration(scene, configuration("backward-euler", 1), 2, 1);
  EXPECT_TRUE(single.ratios.empty());
}

TEST(BenchmarkRun, ConfiguredScene) {
  Scene scene = barScene(kExplicitRegions);
  scene.output.file = "out/run.afsim";
  const Scene bySteps = configuredScene(scene, configuration("trapezoidal", 4, {{"solver", "umfpack"}}), 7);
  EXPECT_EQ(bySteps.integrator.name, "trapezoidal");
  EXPECT_EQ(bySteps.timing.stepsPerFrame, 4);
  EXPECT_EQ(bySteps.timing.timestep, bySteps.timing.frameInterval / 4);
  EXPECT_EQ(bySteps.integrator.options, nlohmann::json({{"solver", "umfpack"}}));
  EXPECT_EQ(bySteps.timing.frameCount, 7);
  EXPECT_TRUE(bySteps.output.file.empty());  // benchmark runs write nothing
  BenchmarkConfiguration byStep = configuration("backward-euler", 0);
  byStep.timestep = 0.025;
  const Scene configured = configuredScene(scene, byStep, 1);
  EXPECT_EQ(configured.timing.stepsPerFrame, 4);
  EXPECT_EQ(configured.timing.timestep, 0.025);
  byStep.timestep = 0.03;  // does not divide the frame interval 1/10 s
  EXPECT_THROW((void)configuredScene(scene, byStep, 1), asyncfem::ValidationError);
  EXPECT_TRUE(isMultirate("async") && isMultirate("multirate-uncoupled"));
  EXPECT_FALSE(isMultirate("backward-euler"));
}

TEST(BenchmarkRun, Formatting) {
  EXPECT_EQ(formatTimestep(1.0 / 120.0), "1/120");
  EXPECT_EQ(formatTimestep(0.3), "0.3");
  EXPECT_EQ(formatRatios({8, 4}), "8,4");
  EXPECT_EQ(formatRatios({}), "");
  EXPECT_EQ(median({3.0, 1.0, 2.0}), 2.0);
  EXPECT_EQ(median({4.0, 1.0, 2.0, 3.0}), 2.5);
  EXPECT_EQ(median({}), 0.0);
}

TEST(ConfigurationRegions, ResolvedAsTheIntegratorResolvesThem) {
  const Scene scene = barScene(kExplicitRegions);
  const Simulation baseline = baselineOf(scene);
  const std::vector<AsyncRegion> regions =
      configurationRegions(scene, baseline, configuration("async", 1, kExplicitRegions));
  ASSERT_EQ(regions.size(), 1u);
  EXPECT_EQ(regions[0].name, "tip");
  EXPECT_EQ(regions[0].ratio, 4);
  for (const int v : regions[0].vertices) EXPECT_GE(baseline.mesh->restPosition(v).x(), 0.75 - 1e-12);
  EXPECT_TRUE(configurationRegions(scene, baseline, configuration("backward-euler", 1)).empty());
}

// h_min / 4 of the finest configuration: backward Euler at 3 steps per frame gives 12
// reference steps; async at 2 steps per frame with ratio 4 gives 2 * 4 * 4.
TEST(ReferenceStepsPerFrame, QuarterOfTheSmallestSubstep) {
  const Scene scene = barScene(kExplicitRegions);
  const Simulation baseline = baselineOf(scene);
  EXPECT_EQ(referenceStepsPerFrame(scene, baseline, {configuration("backward-euler", 3)}), 12);
  EXPECT_EQ(referenceStepsPerFrame(scene, baseline,
                                   {configuration("backward-euler", 3), configuration("async", 2, kExplicitRegions)}),
            32);
  EXPECT_EQ(referenceStepsPerFrame(scene, baseline, {}), 4);  // never coarser than a quarter frame
}

// "regions": "auto" is sized by the ratio the proposal gives (here well above 1: the
// stiff, light tip), not as if the configuration were single-rate.
TEST(ReferenceStepsPerFrame, AutomaticRegionsCountWithTheirRatio) {
  const nlohmann::json automatic = {{"regions", "auto"}, {"auto", {{"modalCheck", false}, {"costCheck", false}}}};
  const Scene scene = barScene(automatic);
  const Simulation baseline = baselineOf(scene);
  const int proposedRatio =
      largestRatio(parseAsyncOptions(scene, *baseline.mesh, baseline.integrator->system().freeDofs, automatic).regions);
  ASSERT_GT(proposedRatio, 1) << "the bar's tip should want a fast region at hL = 0.1 s";
  EXPECT_EQ(referenceStepsPerFrame(scene, baseline, {configuration("async", 1, automatic)}), 4 * proposedRatio);
}

TEST(ErrorGroups, RegionsOfTheFirstMultirateConfigurationThenLAndAll) {
  const nlohmann::json twoRegions = {{"regions",
                                      {{{"name", "tip"}, {"ratio", 4}, {"elementSets", {"tip"}}},
                                       {{"ratio", 2}, {"boxes", {{{"min", {0.45, -1, -1}}, {"max", {0.55, 2, 2}}}}}}}}};
  const Scene scene = barScene(twoRegions);
  const Simulation baseline = baselineOf(scene);
  const std::vector<VertexGroup> groups =
      errorGroups(scene, baseline,
                  {configuration("backward-euler", 1), configuration("async", 1, twoRegions),
                   configuration("async", 1, nlohmann::json::object())});
  ASSERT_EQ(groups.size(), 4u);
  EXPECT_EQ(groups[0].name, "tip");
  EXPECT_EQ(groups[1].name, "S1");  // unnamed: by position
  EXPECT_EQ(groups[2].name, "L");
  EXPECT_EQ(groups[3].name, "all");
  EXPECT_TRUE(groups[3].vertices.empty());
  // The three groups split the vertices.
  EXPECT_EQ(groups[0].vertices.size() + groups[1].vertices.size() + groups[2].vertices.size(),
            static_cast<std::size_t>(baseline.mesh->numVertices()));
  for (const int v : groups[2].vertices) {
    const double x = baseline.mesh->restPosition(v).x();
    EXPECT_TRUE(x < 0.45 || (x > 0.55 && x < 0.75)) << "vertex " << v << " at x = " << x;
  }
  const std::vector<VertexGroup> single = errorGroups(scene, baseline, {configuration("backward-euler", 1)});
  ASSERT_EQ(single.size(), 1u);
  EXPECT_EQ(single[0].name, "all");
}

TEST(ChooseVertex, LargestPeakInTheFirstGroup) {
  Trajectory reference(3, Eigen::VectorXd::Zero(12));  // 4 vertices
  reference[1][3 * 3 + 1] = 5.0;                       // vertex 3 moves most overall
  reference[2][3 * 1 + 2] = -2.0;                      // vertex 1 most among {0, 1, 2}
  reference[0][3 * 2] = 1.0;
  const std::vector<VertexGroup> groups{{"S", {0, 1, 2}}, {"L", {3}}, {"all", {}}};
  EXPECT_EQ(chooseVertex(reference, groups, 4), 1);
  EXPECT_EQ(chooseVertex(reference, {{"all", {}}}, 4), 3);
}

// The linear bar has an exact modal reference; trapezoidal is used when asked for, at
// referenceStepsPerFrame; a corotational bar has no modal reference.
TEST(ComputeReference, ModalWhenPossibleElseTrapezoidal) {
  const Scene scene = barScene(kExplicitRegions);
  const Simulation baseline = baselineOf(scene);
  const std::vector<BenchmarkConfiguration> configs{configuration("async", 1, kExplicitRegions)};
  const BenchmarkReference modal = computeReference(scene, baseline, configs, 3, ReferenceKind::automatic, 5000);
  ASSERT_NE(modal.modal, nullptr);
  EXPECT_EQ(modal.frames.size(), 3u);
  EXPECT_EQ(modal.description.rfind("exact modal solution (", 0), 0u) << modal.description;
  const BenchmarkReference fine = computeReference(scene, baseline, configs, 3, ReferenceKind::trapezoidal, 5000);
  EXPECT_EQ(fine.modal, nullptr);
  EXPECT_EQ(fine.frames.size(), 3u);
  EXPECT_EQ(fine.description.rfind("trapezoidal run at h = 1/160 (requested, ", 0), 0u) << fine.description;
  // Too many DOFs for the dense eigensolve: trapezoidal, saying why; an error when modal is required.
  const BenchmarkReference fallback = computeReference(scene, baseline, configs, 1, ReferenceKind::automatic, 10);
  EXPECT_NE(fallback.description.find("no modal reference: "), std::string::npos) << fallback.description;
  EXPECT_THROW(computeReference(scene, baseline, configs, 1, ReferenceKind::modal, 10), Error);
}

}  // namespace
}  // namespace asyncfem
