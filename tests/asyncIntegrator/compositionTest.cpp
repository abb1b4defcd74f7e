// SPDX-License-Identifier: BSD-3-Clause
// What composes in the one asynchronous integrator (docs/asynchronous-integrator.md, "What
// composes"): the hierarchy solve with run-time regions (two-level and nested partitions),
// and every refused combination refused by chooseStepSolver() with the option's key.
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/asyncIntegrator/stepSolver.hpp>
#include <asyncfem/core/error.hpp>
#include <string>
#include <vector>

#include "asyncTestSystem.hpp"

namespace asyncfem {
namespace {

constexpr double kLargeStep = 5e-3;

RunTimeRegionOptions windows(std::vector<ScheduledRegion> schedule, bool nest) {
  RunTimeRegionOptions options;
  options.schedule = std::move(schedule);
  options.nest = nest;
  return options;
}

double largestDifference(const Integrator& a, const Integrator& b) {
  return std::max(test::relativeDifference(a.displacement(), b.displacement()),
                  test::relativeDifference(a.velocity(), b.velocity()));
}

// Run-time regions through the hierarchy solve ("method": "hierarchy"): the scheduled
// two-level partition gives the structured Schur solve's trajectory to round-off (1e-10
// relative after nine damped, loaded steps of systems with condition numbers ~1e6), and the
// partitions change at the same steps.
TEST(Composition, HierarchySolveTakesRunTimeRegions) {
  const test::TestSystem ts = test::makeTestSystem(0.1, 1e-3);
  const std::vector<int> tip = test::verticesBeyond(ts.mesh, 0.75);
  AsyncOptions hierarchy;
  hierarchy.method = AsyncSolveMethod::hierarchy;
  AsyncOptions exact;
  exact.keptFactors.laggedSchur = false;
  AsyncBackwardEuler structured(ts.system, kLargeStep, {}, exact);
  AsyncBackwardEuler levels(ts.system, kLargeStep, {}, hierarchy);
  structured.setState(ts.u0, ts.v0);
  levels.setState(ts.u0, ts.v0);
  const auto schedule = windows({{"tip", 1.5 * kLargeStep, 5.5 * kLargeStep, tip, 4}}, false);
  structured.setRunTimeRegions(schedule);
  levels.setRunTimeRegions(schedule);
  for (int k = 0; k < 9; ++k) {
    structured.step();
    levels.step();
    EXPECT_EQ(levels.stepSolver(), AsyncStepSolver::hierarchy);
  }
  EXPECT_EQ(structured.stepSolver(), AsyncStepSolver::structuredSchur);
  EXPECT_GT(structured.displacement().norm(), 0.0);
  EXPECT_LT(largestDifference(structured, levels), 1e-10);
  ASSERT_EQ(levels.repartitions().size(), structured.repartitions().size());
  for (std::size_t r = 0; r < levels.repartitions().size(); ++r)
    EXPECT_EQ(levels.repartitions()[r].step, structured.repartitions()[r].step);
}

// Run-time regions that nest (a tip at 16 inside an end at 4, both scheduled): with nest the
// partition keeps both ratios and the integrator switches to the hierarchy solve by itself,
// bit for bit what the same partitions set by hand at the same steps give; without nest the
// two are merged into one region at 16 (the two-level solve).
TEST(Composition, RunTimeRegionsNest) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 1e-3);
  const std::vector<int> tip = test::verticesBeyond(ts.mesh, 0.875);
  const std::vector<int> end = test::verticesBeyond(ts.mesh, 0.625);  // holds the tip
  std::vector<int> endOnly;
  for (const int v : end)
    if (std::find(tip.begin(), tip.end(), v) == tip.end()) endOnly.push_back(v);
  const std::vector<ScheduledRegion> schedule{{"end", 1.5 * kLargeStep, 6.5 * kLargeStep, end, 4},
                                              {"tip", 2.5 * kLargeStep, 4.5 * kLargeStep, tip, 16}};
  AsyncBackwardEuler nested(ts.system, kLargeStep, {});
  AsyncBackwardEuler byHand(ts.system, kLargeStep, {});
  AsyncBackwardEuler merged(ts.system, kLargeStep, {});
  for (Integrator* integrator :
       {static_cast<Integrator*>(&nested), static_cast<Integrator*>(&byHand), static_cast<Integrator*>(&merged)})
    integrator->setState(ts.u0, ts.v0);
  nested.setRunTimeRegions(windows(schedule, true));
  merged.setRunTimeRegions(windows(schedule, false));
  const std::vector<std::vector<AsyncRegion>> byStep{{},
                                                     {},
                                                     {{"end", end, 4}},
                                                     {{"end", endOnly, 4}, {"tip", tip, 16}},
                                                     {{"end", endOnly, 4}, {"tip", tip, 16}},
                                                     {{"end", end, 4}},
                                                     {{"end", end, 4}},
                                                     {},
                                                     {}};
  for (std::size_t k = 0; k < byStep.size(); ++k) {
    if (k == 0 || byStep[k].size() != byStep[k - 1].size() || (k == 5))
      byHand.setUp(RegionPartition(ts.mesh, ts.system.freeDofs, byStep[k]));
    nested.step();
    byHand.step();
    merged.step();
    EXPECT_EQ(nested.partition().numRegions(), static_cast<int>(byStep[k].size())) << "step " << k;
    const bool both = byStep[k].size() == 2;
    EXPECT_EQ(nested.stepSolver(), both ? AsyncStepSolver::hierarchy : AsyncStepSolver::structuredSchur) << k;
    EXPECT_EQ(nested.partition().touching(), both) << "step " << k;
    EXPECT_EQ(merged.stepSolver(), AsyncStepSolver::structuredSchur) << "step " << k;
    EXPECT_EQ((nested.displacement() - byHand.displacement()).cwiseAbs().maxCoeff(), 0.0) << "step " << k;
    EXPECT_EQ((nested.velocity() - byHand.velocity()).cwiseAbs().maxCoeff(), 0.0) << "step " << k;
  }
  // Merged and nested differ (the end took 16 substeps in one, 4 in the other).
  EXPECT_GT(largestDifference(nested, merged), 1e-8);
}

// Twelve regions that touch at one ratio (a row of vertex slabs, each its own region) step
// as the one region of their vertices: the set-up merges them (the same step counts, so the
// same step, Eqs. N1-N6), and the structured Schur solve runs; bit for bit the one region's
// run, and the hierarchy solve's to round-off (1e-10).
TEST(Composition, TouchingRegionsAtOneRatioStepAsOneRegion) {
  const test::TestSystem ts = test::makeTestSystem(0.1, 1e-3);
  std::vector<AsyncRegion> slabs;
  std::vector<int> all;
  for (int k = 0; k < 4; ++k) {
    const double x = 0.5 + 0.125 * k;
    slabs.push_back({"slab" + std::to_string(k), test::verticesOnPlanes(ts.mesh, {x}), 8});
    all.insert(all.end(), slabs.back().vertices.begin(), slabs.back().vertices.end());
  }
  AsyncOptions exact;
  exact.keptFactors.laggedSchur = false;
  AsyncBackwardEuler touching(ts.system, kLargeStep, slabs, exact);
  AsyncBackwardEuler one(ts.system, kLargeStep, {{"all", all, 8}}, exact);
  AsyncOptions hierarchyOptions;
  hierarchyOptions.method = AsyncSolveMethod::hierarchy;
  AsyncBackwardEuler hierarchy(ts.system, kLargeStep, slabs, hierarchyOptions);
  EXPECT_EQ(touching.stepSolver(), AsyncStepSolver::structuredSchur);
  ASSERT_EQ(touching.partition().numRegions(), 1);
  EXPECT_EQ(touching.partition().region(0).name, "slab0+slab1+slab2+slab3");
  for (Integrator* integrator :
       {static_cast<Integrator*>(&touching), static_cast<Integrator*>(&one), static_cast<Integrator*>(&hierarchy)}) {
    integrator->setState(ts.u0, ts.v0);
    for (int k = 0; k < 5; ++k) integrator->step();
  }
  EXPECT_EQ((touching.displacement() - one.displacement()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((touching.velocity() - one.velocity()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LT(largestDifference(touching, hierarchy), 1e-10);
  EXPECT_GT(touching.displacement().norm(), 0.0);
}

/// The key of the AsyncOptionError that building the integrator throws ("" for none).
std::string refusedKey(const test::TestSystem& ts, DynamicSystem system, const std::vector<AsyncRegion>& regions,
                       const AsyncOptions& options) {
  try {
    AsyncBackwardEuler integrator(std::move(system), kLargeStep, regions, options);
  } catch (const AsyncOptionError& e) {
    EXPECT_NE(std::string(e.what()).find(e.key()), std::string::npos) << e.what();
    return e.key();
  }
  (void)ts;
  return "";
}

// The refused cells of the composition table, each by its option's key, and the same
// options accepted where the regions do not touch (the refusal is the hierarchy's, not the
// option's).
TEST(Composition, EveryRefusalNamesItsOption) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 0.0);
  const std::vector<AsyncRegion> touching{{"a", test::verticesOnPlanes(ts.mesh, {0.5}), 2},
                                          {"b", test::verticesOnPlanes(ts.mesh, {0.625}), 4}};
  const std::vector<AsyncRegion> apart{{"a", test::verticesOnPlanes(ts.mesh, {0.25}), 2},
                                       {"b", test::verticesOnPlanes(ts.mesh, {0.625}), 4}};
  const auto with = [](auto change) {
    AsyncOptions options;
    change(options);
    return options;
  };
  const std::vector<std::pair<std::string, AsyncOptions>> cells{
      {"coupling", with([](AsyncOptions& o) { o.coupling = AsyncCoupling::paper; })},
      {"quickSetUp", with([](AsyncOptions& o) { o.keptFactors.quickSetUp = true; })},
      {"substepStatePrediction", with([](AsyncOptions& o) { o.contact.substepStatePrediction = true; })},
      {"method", with([](AsyncOptions& o) { o.method = AsyncSolveMethod::naive; })},
      {"schur", with([](AsyncOptions& o) { o.schur = SchurMode::lu; })},
      {"recovery", with([](AsyncOptions& o) { o.recovery = RecoveryMode::substitution; })},
      {"denseRegionDofs", with([](AsyncOptions& o) { o.denseRegionDofs = 0; })},
  };
  for (const auto& [key, options] : cells) {
    EXPECT_EQ(refusedKey(ts, ts.system, touching, options), key);
    EXPECT_EQ(refusedKey(ts, ts.system, apart, options), "") << key;
  }
  DynamicSystem implicitContact = ts.system;
  implicitContact.externalForceJacobian = [](double, const Eigen::VectorXd&, const Eigen::VectorXd&, VertexJacobian&) {
  };
  // Implicit contact composes with the hierarchy solve (AsyncImplicitContact.*Hierarchy*,
  // *Nested*): accepted on both.
  EXPECT_EQ(refusedKey(ts, implicitContact, touching, {}), "");
  EXPECT_EQ(refusedKey(ts, implicitContact, apart, {}), "");
  const AsyncOptions lu = with([](AsyncOptions& o) { o.nestedSolve = NestedSolve::lu; });
  EXPECT_EQ(refusedKey(ts, ts.system, apart, lu), "nestedSolve");
  EXPECT_EQ(refusedKey(ts, ts.system, touching, lu), "");
  // Run-time regions that may nest are checked when the policy is set, before any step.
  AsyncBackwardEuler quick(ts.system, kLargeStep, {}, with([](AsyncOptions& o) { o.keptFactors.quickSetUp = true; }));
  try {
    quick.setRunTimeRegions(windows({{"a", 0.0, 1.0, touching[0].vertices, 2}}, true));
    FAIL() << "nesting run-time regions accepted the quick set-up";
  } catch (const AsyncOptionError& e) {
    EXPECT_EQ(e.key(), "quickSetUp");
  }
}

}  // namespace
}  // namespace asyncfem
