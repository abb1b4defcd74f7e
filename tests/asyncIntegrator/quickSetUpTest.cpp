// SPDX-License-Identifier: BSD-3-Clause
// AsyncOptions::KeptFactors::quickSetUp: L's system solved by deflated conjugate gradients on the whole
// single-rate system's factor (docs/asynchronous-integrator.md, "Quick set-up"), against
// the exact set-up (Z and the factor of H^{LL*}).
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/core/error.hpp>
#include <memory>
#include <nlohmann/json.hpp>
#include <vector>

#include "asyncTestSystem.hpp"

namespace asyncfem {
namespace {

constexpr double kLargeStep = 5e-3;

AsyncOptions quick(bool on) {
  AsyncOptions options;
  options.keptFactors.quickSetUp = on;
  return options;
}

/// Largest relative difference of displacement and velocity between two runs.
double stateDifference(const Integrator& a, const Integrator& b) {
  return std::max(test::relativeDifference(a.displacement(), b.displacement()),
                  test::relativeDifference(a.velocity(), b.velocity()));
}

/// The exact set-up and the quick one (fastOptions) side by side from the test state.
struct SideBySide {
  SideBySide(const test::TestSystem& ts, const std::vector<AsyncRegion>& regions, const AsyncOptions& exactOptions,
             const AsyncOptions& fastOptions)
      : exact(ts.mesh, ts.system, kLargeStep, regions, exactOptions),
        fast(ts.mesh, ts.system, kLargeStep, regions, fastOptions) {
    exact.setState(ts.u0, ts.v0);
    fast.setState(ts.u0, ts.v0);
  }
  /// One step of both; the quick run's iterations in it.
  long long step() {
    exact.step();
    const long long before = fast.runStats().quickIterations;
    fast.step();
    return fast.runStats().quickIterations - before;
  }
  double difference() const { return stateDifference(exact, fast); }
  AsyncBackwardEuler exact, fast;
};

// Every ratio 1: H^{LL*} is the Schur complement of the single-rate system on L, so the
// borrowed factor is exact and every step takes one iteration. The exact set-up's
// trajectory is matched to round-off (1e-12 relative: one sparse solve against another of
// the same system, over 10 steps of a well-conditioned system). The rent-or-buy rule is
// off: the product with H^{LL*} each iteration adds is what it would eventually buy out.
TEST(QuickSetUp, RatioOneIsExactInOneIteration) {
  const test::TestSystem ts = test::makeTestSystem(0.3, 2e-3);
  const std::vector<AsyncRegion> regions{{"tip", test::verticesBeyond(ts.mesh, 0.75), 1}};
  AsyncOptions options = quick(true);
  options.keptFactors.quickSetUpRebuild = false;
  SideBySide runs(ts, regions, quick(false), options);
  for (int k = 0; k < 10; ++k) runs.step();
  EXPECT_LT(runs.difference(), 1e-12);
  const AsyncBackwardEuler& fast = runs.fast;
  EXPECT_EQ(fast.runStats().quickSteps, 10);
  EXPECT_EQ(fast.runStats().quickIterations, 10);
  EXPECT_EQ(fast.runStats().quickEnds, 0);
}

// Ratio 8: the iterations stop at a relative residual of 1e-10 (laggedSchurTolerance), so
// the trajectory stays within 1e-8 relative of the exact one over 40 steps. The kept
// directions deflate the at most |I|-dimensional space where the preconditioner differs
// from H^{LL*}: the solves need fewer iterations as the run goes on, down to one (the
// rent-or-buy rule off, so that the run stays on the quick path).
TEST(QuickSetUp, DeflationLearnsTheInterface) {
  const test::TestSystem ts = test::makeTestSystem(0.3, 2e-3);
  const std::vector<AsyncRegion> regions{{"tip", test::verticesBeyond(ts.mesh, 0.75), 8}};
  AsyncOptions options = quick(true);
  options.keptFactors.quickSetUpRebuild = false;
  SideBySide runs(ts, regions, quick(false), options);
  std::vector<long long> iterations;
  for (int k = 0; k < 40; ++k) iterations.push_back(runs.step());
  EXPECT_LT(runs.difference(), 1e-8);
  const AsyncBackwardEuler& fast = runs.fast;
  EXPECT_EQ(fast.runStats().quickEnds, 0);
  EXPECT_GT(iterations.front(), 2);
  EXPECT_TRUE(std::is_sorted(iterations.rbegin(), iterations.rend())) << "iterations grew somewhere";
  EXPECT_EQ(iterations.back(), 1);
  EXPECT_LE(fast.runStats().largestQuickResidual, options.keptFactors.laggedSchurTolerance);
}

// With the rent-or-buy rule on (the default), a long run on a cheap-to-factor system
// leaves the quick path for Z and H^{LL*}, and then solves exactly.
TEST(QuickSetUp, TheRentOrBuyRuleBuildsTheFactorWhenItPays) {
  const test::TestSystem ts = test::makeTestSystem(0.3, 2e-3);
  const std::vector<AsyncRegion> regions{{"tip", test::verticesBeyond(ts.mesh, 0.75), 8}};
  SideBySide runs(ts, regions, quick(false), quick(true));
  for (int k = 0; k < 20; ++k) runs.step();
  EXPECT_EQ(runs.fast.runStats().quickEnds, 1);
  EXPECT_LT(runs.fast.runStats().quickSteps, 20);
  EXPECT_LT(runs.difference(), 1e-8);
}

// A new partition on the quick path factors only its regions' A^S: the whole system's
// factor is kept across partitions (same hL), so nothing of L's size is factored again.
TEST(QuickSetUp, ANewPartitionFactorsOnlyItsRegions) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 1e-3);
  AsyncBackwardEuler fast(ts.mesh, ts.system, kLargeStep, {{"tip", test::verticesBeyond(ts.mesh, 0.75), 4}},
                          quick(true));
  fast.setState(ts.u0, ts.v0);
  fast.step();
  const long long before = fast.stats().factorizations;
  fast.setUp(RegionPartition(ts.mesh, ts.system.freeDofs,
                             {{"half", test::verticesBeyond(ts.mesh, 0.5), 8}, {"root", {0, 1, 2}, 2}}));
  EXPECT_EQ(fast.stats().factorizations - before, 2);  // A^S of "half" and of "root"
  AsyncBackwardEuler exact(ts.mesh, ts.system, kLargeStep, {{"tip", test::verticesBeyond(ts.mesh, 0.75), 4}});
  exact.setState(ts.u0, ts.v0);
  exact.step();
  exact.setUp(fast.partition());
  fast.step();
  exact.step();
  EXPECT_LT(stateDifference(exact, fast), 1e-8);
}

// Partitions that shrink L and grow it again: the deflation directions' storage is kept
// across partitions (only their count is reset), so the directions of an earlier partition
// must not leak into a later one's solves. Five steps each, rent-or-buy off so that every
// step stays on the quick path; 1e-8 relative to the exact set-up over the 15 steps.
TEST(QuickSetUp, DeflationStorageKeptAcrossPartitionsOfEverySize) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 1e-3);
  const std::vector<AsyncRegion> small{{"tip", test::verticesBeyond(ts.mesh, 0.75), 4}};
  const std::vector<AsyncRegion> large{{"half", test::verticesBeyond(ts.mesh, 0.5), 8}};
  AsyncOptions options = quick(true);
  options.keptFactors.quickSetUpRebuild = false;
  SideBySide runs(ts, small, quick(false), options);
  for (const std::vector<AsyncRegion>* regions : {&large, &small}) {
    for (int k = 0; k < 5; ++k) runs.step();
    runs.fast.setUp(RegionPartition(ts.mesh, ts.system.freeDofs, *regions));
    runs.exact.setUp(runs.fast.partition());
  }
  long long last = 0;
  for (int k = 0; k < 5; ++k) last = runs.step();
  EXPECT_EQ(runs.fast.runStats().quickSteps, 15);
  EXPECT_EQ(runs.fast.runStats().quickEnds, 0);
  EXPECT_LT(last, runs.fast.runStats().quickIterations / 15);  // still learning from its own solves
  EXPECT_LT(runs.difference(), 1e-8);
}

// Corotational forces: the tangent changes every step, so the kept directions are dropped
// at every refactorization and the borrowed factor (first tangent) preconditions the
// later ones; 1e-8 relative over 15 steps, as for linear forces.
TEST(QuickSetUp, CorotationalForcesStayWithinTheTolerance) {
  const test::TestSystem ts = test::makeTestSystem(test::testSettings(ForceModelType::corotational, 0.3, 2e-3));
  const std::vector<AsyncRegion> regions{{"tip", test::verticesBeyond(ts.mesh, 0.75), 4}};
  AsyncOptions exactOptions = quick(false);
  exactOptions.keptFactors.laggedSchur = false;
  SideBySide runs(ts, regions, exactOptions, quick(true));
  for (int k = 0; k < 15; ++k) runs.step();
  EXPECT_LT(runs.difference(), 1e-8);
  EXPECT_GT(runs.fast.runStats().quickSteps, 0);
  EXPECT_NE(runs.fast.report().resumeCaveat.find("quickSetUp"), std::string::npos);
}

// The scene key reaches the options, is written back by the settings codec, and a typo is
// refused naming the known keys.
TEST(QuickSetUp, SceneKey) {
  const IntegratorContext context = test::barContext();
  const AsyncSettings settings =
      parseAsyncSettings(context, nlohmann::json{{"quickSetUp", true}, {"regions", nlohmann::json::array()}});
  EXPECT_TRUE(settings.solver.keptFactors.quickSetUp);
  EXPECT_EQ(asyncSettingsJson(settings).at("quickSetUp"), true);
  try {
    parseAsyncSettings(context, nlohmann::json{{"quickSetup", true}});
    FAIL() << "a misspelt key was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("quickSetUp"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace asyncfem
