// SPDX-License-Identifier: BSD-3-Clause
// Run-time regions: RunTimeRegionPolicy's decisions and AsyncBackwardEuler's
// re-partitions (fresh and cached set-ups), against integrators set up by hand.
#include <gtest/gtest.h>

#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/asyncIntegrator/runTimeRegions.hpp>
#include <asyncfem/core/error.hpp>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "asyncTestSystem.hpp"

namespace asyncfem {
namespace {

constexpr double kLargeStep = 5e-3;

void expectSameState(const Integrator& a, const Integrator& b) {
  EXPECT_EQ(a.time(), b.time());
  EXPECT_EQ((a.displacement() - b.displacement()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((a.velocity() - b.velocity()).cwiseAbs().maxCoeff(), 0.0);
}

RunTimeRegionOptions scheduleOf(std::vector<ScheduledRegion> windows) {
  RunTimeRegionOptions options;
  options.schedule = std::move(windows);
  return options;
}

// A window open over the whole run is a fixed region: the adaptive run equals the fixed
// one bit for bit (the same set-up, then the same steps).
TEST(RunTimeRegions, AnAlwaysOpenWindowEqualsTheFixedRegion) {
  const test::TestSystem ts = test::makeTestSystem(0.3, 2e-3);
  const std::vector<int> tip = test::verticesBeyond(ts.mesh, 0.75);
  AsyncBackwardEuler fixed(ts.mesh, ts.system, kLargeStep, {{"tip", tip, 4}});
  AsyncBackwardEuler adaptive(ts.mesh, ts.system, kLargeStep, {});
  fixed.setState(ts.u0, ts.v0);
  adaptive.setState(ts.u0, ts.v0);
  adaptive.setRunTimeRegions(scheduleOf({{"tip", 0.0, 1.0, tip, 4}}));
  ASSERT_EQ(adaptive.partition().numRegions(), 1);
  for (int k = 0; k < 5; ++k) {
    fixed.step();
    adaptive.step();
  }
  expectSameState(fixed, adaptive);
  ASSERT_EQ(adaptive.repartitions().size(), 1U);
  EXPECT_EQ(adaptive.repartitions()[0].reason, "initial regions");
  // The summary lists the re-partition, and a resumed run is told that the partition is
  // chosen afresh (it is not in the checkpoint).
  const RunReport report = adaptive.report();
  bool listed = false;
  for (const std::string& line : report.lines) listed = listed || line.find("initial regions") != std::string::npos;
  EXPECT_TRUE(listed);
  EXPECT_NE(report.resumeCaveat.find("run-time regions"), std::string::npos) << report.resumeCaveat;
  EXPECT_TRUE(fixed.report().resumeCaveat.empty()) << fixed.report().resumeCaveat;
  EXPECT_EQ(adaptive.repartitions()[0].fastVertices, static_cast<int>(tip.size()));
}

// A window [2 hL, 4 hL) opens and closes exactly at those large-step boundaries, and the
// run equals one whose partitions are set by hand at the same steps; the second opening of
// the same window takes the cached set-up, with the same result as a fresh one.
TEST(RunTimeRegions, WindowsSwitchAtTheirBoundariesAndTheCacheChangesNothing) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 1e-3);
  const std::vector<int> tip = test::verticesBeyond(ts.mesh, 0.75);
  const std::vector<AsyncRegion> fast{{"tip", tip, 4}};
  AsyncBackwardEuler adaptive(ts.mesh, ts.system, kLargeStep, {});
  AsyncBackwardEuler byHand(ts.mesh, ts.system, kLargeStep, {});
  adaptive.setState(ts.u0, ts.v0);
  byHand.setState(ts.u0, ts.v0);
  // Boundaries half a step away from the step times, so rounding cannot move them.
  adaptive.setRunTimeRegions(scheduleOf(
      {{"tip", 1.5 * kLargeStep, 3.5 * kLargeStep, tip, 4}, {"tip", 5.5 * kLargeStep, 7.5 * kLargeStep, tip, 4}}));
  const std::vector<int> switchAt{2, 4, 6, 8};
  for (int k = 0; k < 9; ++k) {
    for (std::size_t s = 0; s < switchAt.size(); ++s)
      if (k == switchAt[s]) {
        byHand.setUp(RegionPartition(ts.mesh, ts.system.freeDofs, s % 2 == 0 ? fast : std::vector<AsyncRegion>{}));
      }
    adaptive.step();
    byHand.step();
    expectSameState(adaptive, byHand);
  }
  const std::vector<RepartitionRecord>& records = adaptive.repartitions();
  ASSERT_EQ(records.size(), 4U);
  for (std::size_t s = 0; s < records.size(); ++s) {
    EXPECT_EQ(records[s].step, switchAt[s]);
    EXPECT_EQ(records[s].regions, s % 2 == 0 ? 1 : 0);
    EXPECT_EQ(records[s].movedVertices, static_cast<int>(tip.size()));
  }
  // The first opening and closing build; the second ones reuse both set-ups.
  EXPECT_FALSE(records[0].reused);
  EXPECT_TRUE(records[1].reused);  // the empty partition of the constructor
  EXPECT_TRUE(records[2].reused);
  EXPECT_TRUE(records[3].reused);
}

// With room for one set-up, the empty partition (what every contact returns to) is the one
// kept: after A and then B, going back to no region takes the cached set-up.
TEST(RunTimeRegions, TheEmptyPartitionStaysCached) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 0.0);
  RunTimeRegionOptions options =
      scheduleOf({{"a", 1.5 * kLargeStep, 2.5 * kLargeStep, test::verticesBeyond(ts.mesh, 0.75), 4},
                  {"b", 2.5 * kLargeStep, 3.5 * kLargeStep, test::verticesBeyond(ts.mesh, 0.5), 2}});
  options.cacheSize = 1;
  AsyncBackwardEuler adaptive(ts.mesh, ts.system, kLargeStep, {});
  adaptive.setState(ts.u0, ts.v0);
  adaptive.setRunTimeRegions(options);
  for (int k = 0; k < 5; ++k) adaptive.step();
  const std::vector<RepartitionRecord>& records = adaptive.repartitions();
  ASSERT_EQ(records.size(), 3U);
  EXPECT_FALSE(records[0].reused);
  EXPECT_FALSE(records[1].reused);
  EXPECT_EQ(records[2].regions, 0);
  EXPECT_TRUE(records[2].reused);
}

// The contact policy through a stand-in obstacle: the vertices with x above a threshold
// that the test moves. The region appears at once, grown by rings, stays while what is
// needed stays inside it, and goes only after the dwell.
TEST(RunTimeRegions, ContactRegionGrowsAtOnceAndShrinksAfterTheDwell) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 0.0);
  double threshold = 2.0;  // nothing near
  const ObstacleProximity proximity = [&](const Eigen::VectorXd&, double, std::vector<int>& out) {
    out = test::verticesBeyond(ts.mesh, threshold);
  };
  RunTimeRegionOptions options;
  options.contact = true;
  options.contactRatio = 6;
  options.contactRings = 1;
  options.contactLookahead = 0.0;
  options.minDwell = 3;
  RunTimeRegionPolicy policy(ts.mesh, ts.system.freeDofs, options);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(ts.system.numDofs());
  std::vector<AsyncRegion> current;
  std::string reason;
  EXPECT_FALSE(policy.decide(0.0, kLargeStep, zero, zero, proximity, current, 0, reason));
  threshold = 0.99;  // the x = 1 face
  auto next = policy.decide(0.0, kLargeStep, zero, zero, proximity, current, 1, reason);
  ASSERT_TRUE(next);
  EXPECT_EQ(reason, "contact region grows");
  ASSERT_EQ(next->size(), 1U);
  EXPECT_EQ((*next)[0].ratio, 6);
  // The face grown by one ring (needed) and one more (slack): x >= 0.75 on this mesh of
  // 1/8 cubes; with a slack of 2, one ring more again.
  EXPECT_EQ((*next)[0].vertices, test::verticesBeyond(ts.mesh, 0.75));
  {
    RunTimeRegionOptions wider = options;
    wider.contactSlack = 2;
    RunTimeRegionPolicy widerPolicy(ts.mesh, ts.system.freeDofs, wider);
    std::string widerReason;
    const auto widerNext = widerPolicy.decide(0.0, kLargeStep, zero, zero, proximity, {}, 1, widerReason);
    ASSERT_TRUE(widerNext);
    ASSERT_EQ(widerNext->size(), 1U);
    EXPECT_EQ((*widerNext)[0].vertices, test::verticesBeyond(ts.mesh, 0.625));
  }
  current = *next;
  threshold = 0.85;  // still inside the region: kept
  EXPECT_FALSE(policy.decide(0.0, kLargeStep, zero, zero, proximity, current, 1, reason));
  threshold = 2.0;  // contact over: kept until the dwell has passed
  EXPECT_FALSE(policy.decide(0.0, kLargeStep, zero, zero, proximity, current, 2, reason));
  next = policy.decide(0.0, kLargeStep, zero, zero, proximity, current, 3, reason);
  ASSERT_TRUE(next);
  EXPECT_TRUE(next->empty());
  EXPECT_EQ(reason, "contact ends");
  current = *next;
  threshold = 0.6;  // beyond the old region: grows at once whatever the dwell
  next = policy.decide(0.0, kLargeStep, zero, zero, proximity, current, 0, reason);
  ASSERT_TRUE(next);
  EXPECT_EQ(reason, "contact region grows");
}

// A cached set-up stands in for the policy's proposal when it covers what is needed, also
// beside a schedule, as long as it gives the windows' vertices exactly the ratio they have
// now: the window's region while it is open, nothing extra once it has closed.
TEST(RunTimeRegions, CachedSetUpsStandInBesideASchedule) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 0.0);
  const std::vector<int> root = [&] {
    std::vector<int> out;
    for (int v = 0; v < ts.mesh.numVertices(); ++v)
      if (ts.mesh.restPosition(v).x() > 0.2 && ts.mesh.restPosition(v).x() < 0.3) out.push_back(v);
    return out;
  }();
  RunTimeRegionOptions options = scheduleOf({{"window", 0.0, 1.0, root, 4}});
  options.contact = true;
  options.contactRatio = 6;
  options.contactRings = 0;
  options.contactLookahead = 0.0;
  const ObstacleProximity proximity = [&](const Eigen::VectorXd&, double, std::vector<int>& out) {
    out = test::verticesBeyond(ts.mesh, 0.9);
  };
  RunTimeRegionPolicy policy(ts.mesh, ts.system.freeDofs, options);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(ts.system.numDofs());
  const std::vector<AsyncRegion> proposal{{"window", root, 4}, {"contact", test::verticesBeyond(ts.mesh, 0.9), 6}};
  const std::vector<AsyncRegion> larger{{"window", root, 4}, {"contact", test::verticesBeyond(ts.mesh, 0.7), 6}};
  const std::vector<AsyncRegion> withoutWindow{{"contact", test::verticesBeyond(ts.mesh, 0.7), 6}};
  EXPECT_TRUE(policy.canServe(larger, proposal, 0.5, kLargeStep, zero, zero, proximity));
  EXPECT_FALSE(policy.canServe(withoutWindow, proposal, 0.5, kLargeStep, zero, zero, proximity));  // window open
  EXPECT_FALSE(policy.canServe(larger, proposal, 2.0, kLargeStep, zero, zero, proximity));         // window closed
  // Closed: a contact region a layer larger serves (within the shrink factor of 2).
  const std::vector<AsyncRegion> contactOnly{{"contact", test::verticesBeyond(ts.mesh, 0.8), 6}};
  EXPECT_TRUE(policy.canServe(contactOnly, {proposal[1]}, 2.0, kLargeStep, zero, zero, proximity));
  // A region on a window's vertex at a higher ratio than the window's is not a stand-in either.
  const std::vector<AsyncRegion> faster{{"window", root, 8}, {"contact", test::verticesBeyond(ts.mesh, 0.7), 6}};
  EXPECT_FALSE(policy.canServe(faster, proposal, 0.5, kLargeStep, zero, zero, proximity));
}

// Regions that touch (an element with vertices in both) are merged at the larger ratio,
// and vertices without a free DOF are left out (the clamped face x = 0 here).
TEST(RunTimeRegions, TouchingWindowsMergeAndFixedVerticesAreLeftOut) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 0.0);
  std::vector<int> clampedEnd, nextLayer;
  for (int v = 0; v < ts.mesh.numVertices(); ++v) {
    const double x = ts.mesh.restPosition(v).x();
    if (x < 1e-9) clampedEnd.push_back(v);
    if (std::abs(x - 0.125) < 1e-9) nextLayer.push_back(v);
  }
  RunTimeRegionPolicy policy(ts.mesh, ts.system.freeDofs,
                             scheduleOf({{"a", 0.0, 1.0, clampedEnd, 2}, {"b", 0.0, 1.0, nextLayer, 5}}));
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(ts.system.numDofs());
  const std::vector<AsyncRegion> wanted = policy.wanted(0.0, kLargeStep, zero, zero, nullptr);
  ASSERT_EQ(wanted.size(), 1U);
  EXPECT_EQ(wanted[0].name, "a+b");
  EXPECT_EQ(wanted[0].ratio, 5);
  EXPECT_EQ(wanted[0].vertices, nextLayer);
  // The merged region is a valid partition.
  EXPECT_FALSE(RegionPartition(ts.mesh, ts.system.freeDofs, wanted).touching());
}

TEST(RunTimeRegions, BadOptionsAreErrors) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 0.0);
  const auto expectError = [&](const RunTimeRegionOptions& options, const std::string& part) {
    try {
      RunTimeRegionPolicy policy(ts.mesh, ts.system.freeDofs, options);
      FAIL() << "expected a ValidationError mentioning " << part;
    } catch (const ValidationError& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  RunTimeRegionOptions options = scheduleOf({{"w", 1.0, 1.0, {0}, 2}});
  expectError(options, "schedule[0]: end must be after start");
  options = scheduleOf({{"w", 0.0, 1.0, {ts.mesh.numVertices()}, 2}});
  expectError(options, "out of range");
  options = RunTimeRegionOptions{};
  options.shrinkFactor = 0.5;
  expectError(options, "shrink");
  options = RunTimeRegionOptions{};
  options.indicator = true;
  options.indicatorRatio = 1;
  expectError(options, "indicator tolerance must be > 0, ratio >= 2");
  // The contact policy needs obstacles.
  AsyncBackwardEuler async(ts.mesh, ts.system, kLargeStep, {});
  RunTimeRegionOptions contact;
  contact.contact = true;
  EXPECT_THROW(async.setRunTimeRegions(contact), ValidationError);
}

// The indicator (Eq. R1): a velocity history with a constant acceleration has no second
// difference, so no region; a kick at the x = 1 face gives those vertices
// e = |kick| / 2 against tolerance times the RMS speed, a power-of-two ratio from it
// (capped), and the face grown by one ring of hysteresis as the region.
TEST(RunTimeRegions, IndicatorMarksWhereTheLargeStepErrs) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 0.0);
  const int n = ts.mesh.numVertices();
  const std::vector<int> face = test::verticesBeyond(ts.mesh, 0.99);
  const auto uniform = [&](double speed) {
    Eigen::VectorXd v = Eigen::VectorXd::Zero(3 * n);
    for (int vertex = 0; vertex < n; ++vertex) v[3 * vertex] = speed;
    return ts.system.freeDofs.expand(ts.system.freeDofs.restrict(v));  // fixed DOFs at rest
  };
  const auto rmsSpeed = [&](const Eigen::VectorXd& v) {
    double sum = 0.0;
    int moving = 0;
    for (int vertex = 0; vertex < n; ++vertex) {
      if (ts.system.freeDofs.fullToFree()[static_cast<std::size_t>(3 * vertex)] < 0) continue;
      sum += v.segment<3>(3 * vertex).squaredNorm();
      ++moving;
    }
    return std::sqrt(sum / moving);
  };
  std::set<int> regimes;  // the kicks reach the floor, the rounding and the cap of the rule
  // (kick, largest ratio): the wanted ratio grows with the kick but saturates near 14 (the
  // kicked face dominates the RMS speed), so the cap is reached with a cap of 8.
  for (const auto& [kick, cap] : std::vector<std::pair<double, int>>{{0.6, 16}, {3.0, 16}, {50.0, 16}, {50.0, 8}}) {
    RunTimeRegionOptions options;
    options.indicator = true;
    options.indicatorTolerance = 0.1;
    options.indicatorRatio = cap;
    options.indicatorRings = 0;
    RunTimeRegionPolicy policy(ts.mesh, ts.system.freeDofs, options);
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(3 * n);
    std::string reason;
    const std::vector<AsyncRegion> none;
    // Constant acceleration: v = 1, 1.5, 2 (and 2.5 next) along x.
    for (int k = 0; k < 3; ++k)
      EXPECT_FALSE(policy.decide(k * kLargeStep, kLargeStep, zero, uniform(1.0 + 0.5 * k), nullptr, none, 10, reason))
          << "step " << k;
    Eigen::VectorXd kicked = uniform(2.5);
    for (int vertex : face) kicked[3 * vertex + 1] += kick;
    const auto next = policy.decide(3 * kLargeStep, kLargeStep, zero, kicked, nullptr, none, 10, reason);
    ASSERT_TRUE(next) << "kick " << kick;
    EXPECT_EQ(reason, "indicator region grows");
    ASSERT_EQ(next->size(), 1U);
    // Eq. R1 from the definition: the kicked face's velocity second difference is the kick,
    // e_v = kick / 2, against tolerance x RMS speed. The documented rule, checked as its
    // properties: a power of two, at most indicatorRatio, and the smallest one that reaches
    // e_v / (tolerance x speed) where the cap allows (2 at least).
    const double want = 0.5 * kick / (options.indicatorTolerance * rmsSpeed(kicked));
    const int ratio = (*next)[0].ratio;
    EXPECT_EQ(ratio & (ratio - 1), 0) << "kick " << kick << ": ratio " << ratio << " is not a power of two";
    EXPECT_GE(ratio, 2);
    EXPECT_LE(ratio, options.indicatorRatio);
    if (want >= options.indicatorRatio) {
      EXPECT_EQ(ratio, options.indicatorRatio) << "kick " << kick << ", wanted " << want;
    } else {
      EXPECT_GE(ratio, want) << "kick " << kick;
      if (ratio > 2) {
        EXPECT_LT(ratio / 2, want) << "kick " << kick << ": a smaller power of two reaches " << want;
      }
    }
    regimes.insert(want <= 2.0 ? 0 : want >= options.indicatorRatio ? 2 : 1);
    EXPECT_EQ((*next)[0].vertices, test::verticesBeyond(ts.mesh, 0.875));
  }
  EXPECT_EQ(regimes.size(), 3U);
}

// A run with the indicator: a random start state (large velocity second differences) makes
// the policy set up a region once three large-step velocities are known (step 2), and the
// partition it chose is a valid one the run continues with.
TEST(RunTimeRegions, IndicatorRunsInTheIntegrator) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 1e-3);
  AsyncBackwardEuler async(ts.mesh, ts.system, kLargeStep, {});
  async.setState(ts.u0, ts.v0);
  RunTimeRegionOptions options;
  options.indicator = true;
  async.setRunTimeRegions(options);
  for (int k = 0; k < 6; ++k) async.step();
  ASSERT_FALSE(async.repartitions().empty());
  EXPECT_EQ(async.repartitions()[0].step, 2);
  EXPECT_EQ(async.repartitions()[0].reason, "indicator region grows");
  EXPECT_GT(async.repartitions()[0].fastVertices, 0);
  EXPECT_TRUE(async.displacement().allFinite());
}

IntegratorContext barContext(bool hasContact) {
  test::TestSystem ts = test::makeTestSystem(0, 0);
  IntegratorContext context;
  context.mesh = std::make_shared<const TetMesh>(ts.mesh);
  context.system = std::move(ts.system);
  context.timestep = kLargeStep;
  context.hasContact = hasContact;
  context.sourceName = "scene.json";
  return context;
}

std::string parseError(const IntegratorContext& context, const nlohmann::json& options) {
  try {
    (void)parseAsyncSettings(context, options);
  } catch (const ValidationError& e) {
    return e.what();
  }
  return "";
}

// The scene's "regions": {"adaptive": ...}: read, written back, and its errors name the key.
TEST(RunTimeRegions, SceneKeys) {
  const nlohmann::json options = nlohmann::json::parse(R"({"regions": {"adaptive": {
      "schedule": [{"name": "tip", "ratio": 4, "start": 0.1, "end": 0.2, "boxes": [{"min": [0.74, -1, -1], "max": [2, 2, 2]}]}],
      "minDwell": 5, "shrink": 3, "cache": 2}}})");
  const AsyncSettings parsed = parseAsyncSettings(barContext(false), options);
  ASSERT_TRUE(parsed.adaptive);
  ASSERT_EQ(parsed.adaptive->schedule.size(), 1U);
  EXPECT_EQ(parsed.adaptive->schedule[0].start, 0.1);
  EXPECT_EQ(parsed.adaptive->schedule[0].end, 0.2);
  EXPECT_EQ(parsed.adaptive->schedule[0].ratio, 4);
  EXPECT_EQ(parsed.adaptive->minDwell, 5);
  EXPECT_EQ(parsed.adaptive->cacheSize, 2);
  EXPECT_FALSE(parsed.adaptive->contact);
  EXPECT_EQ(asyncSettingsJson(parsed)["regions"], options["regions"]);

  const IntegratorContext bar = barContext(false);
  EXPECT_NE(parseError(bar, nlohmann::json::parse(R"({"regions": {"adaptive": {"contact": {}}}})"))
                .find("scene.json: integrator.options.regions.adaptive.contact: needs obstacles"),
            std::string::npos);
  EXPECT_NE(parseError(bar, nlohmann::json::parse(R"({"regions": {"adaptive": {}}})")).find("give at least one policy"),
            std::string::npos);
  EXPECT_NE(
      parseError(bar, nlohmann::json::parse(
                          R"({"regions": {"adaptive": {"schedule": [{"ratio": 2, "vertices": [1], "strat": 0}]}}})"))
          .find("schedule[0].strat"),
      std::string::npos);
  EXPECT_NE(
      parseError(barContext(true), nlohmann::json::parse(R"({"regions": {"adaptive": {"contact": {"ratio": 1}}}})"))
          .find("contact.ratio"),
      std::string::npos);
  const AsyncSettings slack = parseAsyncSettings(
      barContext(true), nlohmann::json::parse(R"({"regions": {"adaptive": {"contact": {"slack": 3}}}})"));
  ASSERT_TRUE(slack.adaptive);
  EXPECT_EQ(slack.adaptive->contactSlack, 3);
  EXPECT_NE(
      parseError(barContext(true), nlohmann::json::parse(R"({"regions": {"adaptive": {"contact": {"slack": -1}}}})"))
          .find("contact.slack"),
      std::string::npos);
  const AsyncSettings indicator = parseAsyncSettings(
      bar,
      nlohmann::json::parse(R"({"regions": {"adaptive": {"indicator": {"tolerance": 0.2, "ratio": 8, "rings": 2}}}})"));
  ASSERT_TRUE(indicator.adaptive);
  EXPECT_TRUE(indicator.adaptive->indicator);
  EXPECT_EQ(indicator.adaptive->indicatorTolerance, 0.2);
  EXPECT_EQ(indicator.adaptive->indicatorRatio, 8);
  EXPECT_EQ(indicator.adaptive->indicatorRings, 2);
  EXPECT_NE(parseError(bar, nlohmann::json::parse(R"({"regions": {"adaptive": {"indicator": {"tolerance": 0}}}})"))
                .find("indicator.tolerance: must be > 0"),
            std::string::npos);
  EXPECT_NE(parseError(bar, nlohmann::json::parse(R"({"regions": {"adaptive": {"indicator": {"tol": 0.1}}}})"))
                .find("indicator.tol"),
            std::string::npos);
}

}  // namespace
}  // namespace asyncfem
