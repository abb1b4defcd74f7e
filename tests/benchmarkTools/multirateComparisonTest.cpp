// SPDX-License-Identifier: BSD-3-Clause
// Multirate runs against single-rate backward Euler on made-up measurements whose answers
// are known in closed form: costs and errors that are powers of the timestep (straight
// lines in log-log, which the interpolation reproduces exactly), and sinusoidal vertex
// motion sampled over whole periods.
#include <gtest/gtest.h>

#include <asyncfem/benchmarkTools/multirateComparison.hpp>
#include <cmath>
#include <numbers>

namespace asyncfem {
namespace {

// The interpolation takes logs and exponentials of values of order 1e-3..1e9: a few
// rounding errors of each, far below 1e-12 relative.
constexpr double kRoundOff = 1e-12;

void expectRelativelyClose(double actual, double expected, double tolerance = kRoundOff) {
  EXPECT_LE(std::abs(actual - expected), tolerance * std::max({1.0, std::abs(actual), std::abs(expected)}))
      << actual << " vs " << expected;
}

BenchmarkRun measuredRun(const std::string& integrator, double timestep, double seconds, double flops,
                         std::map<std::string, double> errors) {
  BenchmarkRun run;
  run.configuration.integrator = integrator;
  run.configuration.label = integrator + " h=" + std::to_string(timestep);
  run.timestep = timestep;
  run.completed = true;
  run.medianSecondsPerFrame = seconds;
  run.factorFlopsPerFrame = flops;
  run.errors = std::move(errors);
  return run;
}

// Backward Euler at h = 1/4 .. 1/32 with time 1e-3 / h s, flops 1e6 / h and error 0.2 h
// (group "all"); one multirate run of 1e-2 s, 2e7 flops and error 0.01; an incomplete
// run of each kind with absurd numbers that must be ignored.
std::vector<BenchmarkRun> costErrorLadder() {
  std::vector<BenchmarkRun> runs;
  for (const double h : {0.25, 0.125, 0.0625, 0.03125}) {
    runs.push_back(measuredRun("backward-euler", h, 1e-3 / h, 1e6 / h, {{"all", 0.2 * h}}));
  }
  runs.push_back(measuredRun("async", 0.25, 1e-2, 2e7, {{"all", 0.01}}));
  BenchmarkRun unstable = measuredRun("backward-euler", 0.5, 1e-9, 1.0, {{"all", 1e9}});
  unstable.completed = false;
  runs.push_back(unstable);
  BenchmarkRun unstableAsync = measuredRun("async", 0.5, 1e-9, 1.0, {{"all", 1e9}});
  unstableAsync.completed = false;
  runs.push_back(unstableAsync);
  return runs;
}

// Only completed backward Euler runs with a positive cost of the kind and a positive error
// of the group are points.
TEST(BackwardEulerPoints, CompletedRunsWithCostAndError) {
  std::vector<BenchmarkRun> runs = costErrorLadder();
  runs[1].medianSecondsPerFrame = 0.0;  // not timed: no time point, still a flops point
  runs[2].errors.clear();
  const std::vector<SingleRatePoint> byTime = backwardEulerPoints(runs, CostKind::time, "all");
  ASSERT_EQ(byTime.size(), 2u);
  EXPECT_EQ(byTime[0].timestep, 0.25);
  EXPECT_EQ(byTime[1].timestep, 0.03125);
  EXPECT_EQ(byTime[1].cost, 1e-3 / 0.03125);
  EXPECT_EQ(byTime[1].error, 0.2 * 0.03125);
  const std::vector<SingleRatePoint> byFlops = backwardEulerPoints(runs, CostKind::flops, "all");
  ASSERT_EQ(byFlops.size(), 3u);
  EXPECT_EQ(byFlops[1].cost, 1e6 / 0.125);
  EXPECT_TRUE(backwardEulerPoints(runs, CostKind::time, "tip").empty());
}

TEST(EqualAnswers, KnownAnswersOnAPowerLawLadder) {
  const std::vector<BenchmarkRun> runs = costErrorLadder();
  const std::vector<EqualAnswers> answers = equalAnswers(runs, {"all"});
  ASSERT_EQ(answers.size(), 2u);  // one completed multirate run, time and flops
  for (const EqualAnswers& a : answers) {
    SCOPED_TRACE(toString(a.costKind));
    EXPECT_EQ(a.run, &runs[4]);
    EXPECT_EQ(a.group, "all");
    EXPECT_TRUE(a.problem.empty()) << a.problem;
    // Equal cost: time 1e-3 / h = 1e-2 at h = 0.1 (flops 1e6 / h = 2e7 at h = 0.05); BE error 0.2 h there.
    const double equalCostStep = a.costKind == CostKind::time ? 0.1 : 0.05;
    expectRelativelyClose(a.atEqualCost.timestep, equalCostStep);
    expectRelativelyClose(a.atEqualCost.error, 0.2 * equalCostStep);
    EXPECT_FALSE(a.atEqualCost.extrapolated);
    // Equal error: 0.2 h = 0.01 at h = 0.05, where BE costs 2e-2 s or 2e7 flops.
    expectRelativelyClose(a.atEqualError.timestep, 0.05);
    expectRelativelyClose(a.atEqualError.cost, a.costKind == CostKind::time ? 2e-2 : 2e7);
    EXPECT_FALSE(a.atEqualError.extrapolated);
  }
  EXPECT_EQ(answers[0].costKind, CostKind::time);
  EXPECT_EQ(answers[1].costKind, CostKind::flops);
}

TEST(EqualAnswers, OutsideTheMeasuredRangeIsMarkedExtrapolated) {
  std::vector<BenchmarkRun> runs = costErrorLadder();
  runs[4].medianSecondsPerFrame = 1e-1;  // BE would need h = 0.01 < 1/32
  const std::vector<EqualAnswers> answers = equalAnswers(runs, {"all"});
  ASSERT_EQ(answers[0].costKind, CostKind::time);
  EXPECT_TRUE(answers[0].atEqualCost.extrapolated);
  expectRelativelyClose(answers[0].atEqualCost.timestep, 0.01);  // the end segment extended: still a power law
  EXPECT_FALSE(answers[0].atEqualError.extrapolated);
}

TEST(EqualAnswers, ProblemsInsteadOfAnswers) {
  std::vector<BenchmarkRun> runs = costErrorLadder();
  runs[4].errors["tip"] = 0.01;  // no backward Euler run has an error for "tip"
  const std::vector<EqualAnswers> answers = equalAnswers(runs, {"tip", "missing"});
  ASSERT_EQ(answers.size(), 4u);
  EXPECT_NE(answers[0].problem.find("fewer than two"), std::string::npos) << answers[0].problem;
  for (BenchmarkRun& run : runs) run.errors["missing"] = 0.1;
  runs[4].errors.erase("missing");
  const std::vector<EqualAnswers> noError = equalAnswers(runs, {"missing"});
  ASSERT_EQ(noError.size(), 2u);
  EXPECT_NE(noError[0].problem.find("no error for group missing"), std::string::npos) << noError[0].problem;
}

// One vertex (index 1 of 2) vibrating along x about c = 0.3 at 3 Hz, sampled at 30 frames
// per s (10 samples per period), so every window of whole periods has mean c and mean
// square amplitude A^2 / 2 exactly.
struct Vibration {
  std::vector<double> times;
  Trajectory reference;
};

Vibration vibration(int frames) {
  Vibration out;
  const double omega = 2.0 * std::numbers::pi * 3.0, amplitude = 0.05, centre = 0.3;
  for (int k = 0; k < frames; ++k) {
    const double t = (k + 1) / 30.0;
    out.times.push_back(t);
    Eigen::VectorXd u = Eigen::VectorXd::Zero(6);
    u[3] = centre + amplitude * std::sin(omega * t);
    out.reference.push_back(u);
  }
  return out;
}

// The run: the same motion at `scale` times the amplitude and shifted in phase.
Trajectory scaledVibration(const Vibration& v, double scale) {
  Trajectory run = v.reference;
  const double omega = 2.0 * std::numbers::pi * 3.0;
  for (std::size_t k = 0; k < run.size(); ++k) run[k][3] = 0.3 + scale * 0.05 * std::sin(omega * v.times[k] + 1.0);
  return run;
}

// Sums of sin and sin^2 over whole periods cancel up to a few rounding errors per sample.
TEST(MotionKeptAfterRelease, AmplitudeRatioOnWholePeriods) {
  const Vibration v = vibration(90);
  Trajectory run = scaledVibration(v, 0.5);
  // Frames up to the release (t <= 1 s) do not count, however wrong they are.
  for (std::size_t k = 0; k < 30; ++k) run[k][3] = 1e3;
  expectRelativelyClose(motionKeptAfterRelease(run, v.reference, v.times, 1.0, INFINITY, 1), 0.5);
  // Nor do frames after `until` (t in (1, 2]: three periods).
  for (std::size_t k = 60; k < 90; ++k) run[k][3] = -1e3;
  expectRelativelyClose(motionKeptAfterRelease(run, v.reference, v.times, 1.0, 2.0, 1), 0.5);
  // The run keeps everything: 1, phase ignored.
  expectRelativelyClose(motionKeptAfterRelease(scaledVibration(v, 1.0), v.reference, v.times, 1.0, 2.0, 1), 1.0);
}

TEST(MotionKeptAfterRelease, UndefinedWithoutFramesOrMotion) {
  const Vibration v = vibration(60);
  EXPECT_TRUE(std::isnan(motionKeptAfterRelease(v.reference, v.reference, v.times, 5.0, INFINITY, 1)));
  // Vertex 0 never moves in the reference.
  EXPECT_TRUE(std::isnan(motionKeptAfterRelease(v.reference, v.reference, v.times, 0.0, INFINITY, 0)));
}

TEST(KeptMotionWindow, AfterTheLastLoadOrAsGiven) {
  PiecewiseConstantLoad load;
  load.breakpoints = {0.5, 1.0};
  EXPECT_EQ(keptMotionWindow(load, {}), std::make_pair(1.0, double(INFINITY)));
  EXPECT_EQ(keptMotionWindow(load, {2.0, 3.0}), std::make_pair(2.0, 3.0));
  EXPECT_EQ(keptMotionWindow(load, {0.2, 3.0}), std::make_pair(1.0, 3.0));  // never before the loads end
  EXPECT_EQ(keptMotionWindow(PiecewiseConstantLoad{}, {}).first, 0.0);
}

// Backward Euler keeps 2 h of the motion at 1e-3 / h s and 1e6 / h flops per frame (a
// power law: interpolated exactly); the multirate run keeps 0.8 at 5e-3 s and 1e7 flops,
// where BE keeps 2 * 0.2 = 0.4 and 2 * 0.1 = 0.2.
TEST(KeptMotionComparison, AgainstBackwardEulerAtEqualTimeAndFlops) {
  const Vibration v = vibration(60);
  std::vector<BenchmarkRun> runs;
  for (const double h : {0.25, 0.125, 0.0625}) {
    runs.push_back(measuredRun("backward-euler", h, 1e-3 / h, 1e6 / h, {}));
    runs.back().frames = scaledVibration(v, 2.0 * h);
  }
  runs.push_back(measuredRun("async", 0.25, 5e-3, 1e7, {}));
  runs.back().frames = scaledVibration(v, 0.8);
  const std::vector<KeptMotion> rows = keptMotionComparison(runs, v.reference, v.times, 0.0, INFINITY, 1);
  ASSERT_EQ(rows.size(), 4u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_FALSE(rows[i].compared);
    expectRelativelyClose(rows[i].kept, 2.0 * runs[i].timestep);
  }
  ASSERT_TRUE(rows[3].compared);
  ASSERT_TRUE(rows[3].atEqualTime && rows[3].atEqualFlops);
  expectRelativelyClose(rows[3].kept, 0.8);
  expectRelativelyClose(rows[3].atEqualTime->error, 0.4);
  expectRelativelyClose(rows[3].atEqualFlops->error, 0.2);
  // With one backward Euler run there is nothing to interpolate.
  runs.erase(runs.begin(), runs.begin() + 2);
  EXPECT_FALSE(keptMotionComparison(runs, v.reference, v.times, 0.0, INFINITY, 1).back().compared);
}

TEST(MotionBands, EdgesAndLargestRatio) {
  const std::vector<double> edges = motionBandEdges(0.01, 16);
  ASSERT_EQ(edges.size(), 4u);
  expectRelativelyClose(edges[1], 30.0);
  expectRelativelyClose(edges[2], 100.0);
  expectRelativelyClose(edges[3], 1600.0);
  std::vector<BenchmarkRun> runs(2);
  EXPECT_EQ(largestRunRatio(runs), 8);  // no multirate run: the default
  runs[0].ratios = {1};
  EXPECT_EQ(largestRunRatio(runs), 8);
  runs[0].ratios = {4, 16};
  runs[1].ratios = {8};
  EXPECT_EQ(largestRunRatio(runs), 16);
}

TEST(EqualCostFigureRuns, CoarsestStepNearestTimeAndTheScenesOwnRatios) {
  std::vector<BenchmarkRun> runs;
  for (const auto& [h, seconds] : {std::pair{0.25, 1e-3}, {0.125, 2e-3}, {0.0625, 4e-3}}) {
    runs.push_back(measuredRun("backward-euler", h, seconds, 0.0, {}));
  }
  runs.push_back(measuredRun("async", 0.25, 3.9e-3, 0.0, {}));
  runs.back().configuration.options["schur"] = "lu";
  runs.push_back(measuredRun("async", 0.25, 2.2e-3, 0.0, {}));
  runs.push_back(measuredRun("async", 0.25, 1e-3, 0.0, {}));
  runs[3].ratios = runs[4].ratios = {8};
  runs[5].ratios = {4};
  BenchmarkRun unstable = measuredRun("backward-euler", 1.0, 2.2e-3, 0.0, {});
  unstable.completed = false;
  runs.push_back(unstable);
  for (BenchmarkRun& run : runs) run.frames.resize(run.completed ? 3 : 1, Eigen::VectorXd::Zero(3));
  const EqualCostFigureRuns figure = equalCostFigureRuns(runs, {8});
  EXPECT_EQ(figure.coarse, &runs[0]);
  EXPECT_EQ(figure.multirate, &runs[4]);  // plain, the scene's ratios
  EXPECT_EQ(figure.equalCost, &runs[1]);  // 2e-3 s is nearest 2.2e-3 s
  // No run with the scene's ratios: the first multirate run, whose time is nearest 4e-3.
  const EqualCostFigureRuns other = equalCostFigureRuns(runs, {16});
  EXPECT_EQ(other.multirate, &runs[3]);
  EXPECT_EQ(other.equalCost, &runs[2]);
  runs.resize(3);
  EXPECT_EQ(equalCostFigureRuns(runs, {8}).multirate, nullptr);
}

}  // namespace
}  // namespace asyncfem
