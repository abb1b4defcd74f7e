// SPDX-License-Identifier: BSD-3-Clause
// Multirate runs against single-rate backward Euler measured in the same benchmark: the
// equal-cost and equal-error answers, and the motion each run keeps after the loads end.
#pragma once

#include <asyncfem/benchmarkTools/benchmarkRun.hpp>
#include <asyncfem/benchmarkTools/costInterpolation.hpp>
#include <asyncfem/benchmarkTools/errorMetrics.hpp>
#include <asyncfem/benchmarkTools/modalReference.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace asyncfem {

/// The cost a comparison is made at: wall time per frame (s, median over repeats) or
/// factor + solve flops per frame.
enum class CostKind { time, flops };

/// "time" or "flops".
std::string toString(CostKind kind);

/// The run's cost per frame of that kind (seconds or flops).
double runCost(const BenchmarkRun& run, CostKind kind);

/// The single-rate backward Euler runs among results that completed with a positive cost
/// of `kind` and a positive error for `group`, as interpolation points (timestep, cost,
/// error), in the order of results.
std::vector<SingleRatePoint> backwardEulerPoints(const std::vector<BenchmarkRun>& results, CostKind kind,
                                                 const std::string& group);

/// One multirate run against backward Euler for one vertex group and cost kind.
struct EqualAnswers {
  const BenchmarkRun* run = nullptr;  ///< points into the results given to equalAnswers()
  std::string group;
  CostKind costKind = CostKind::time;
  EqualCostAnswer atEqualCost;    ///< BE step of the run's cost, and BE's error there
  EqualErrorAnswer atEqualError;  ///< BE step of the run's error, and BE's cost there
  std::string problem;            ///< non-empty: no answer, and why
};

/// For every group name, then every cost kind (time, flops), then every completed
/// multirate run in order: singleRateAtEqualCost() and singleRateAtEqualError() against the
/// backwardEulerPoints() of that group and kind. A run gets a problem instead of answers
/// when there are fewer than two points, when it has no error for the group, or when the
/// interpolation throws (a flat curve).
std::vector<EqualAnswers> equalAnswers(const std::vector<BenchmarkRun>& results,
                                       const std::vector<std::string>& groupNames);

/// How much of one vertex's free vibration a run keeps in the time window (release, until]:
///
///     sqrt( sum_k |u_k(v) - c|^2 / sum_k |r_k(v) - c|^2 ),   c = mean_k r_k(v),
///
/// over the frames k with release < times[k] <= until (times: s, one per reference frame;
/// run frames beyond the run's end are left out of both sums), u the run, r the reference,
/// c the reference's mean position over the window (the equilibrium it vibrates about).
/// 1 keeps all of the motion, below 1 is damping; phase is ignored (what Figures 4 and 7
/// of Zhao, Li & Barbič 2016 show). NaN when no frame lies in the window or the reference
/// does not move there.
double motionKeptAfterRelease(const Trajectory& run, const Trajectory& reference, const std::vector<double>& times,
                              double release, double until, int vertex);

/// The window of the motion-kept comparison: from the end of the last load window
/// (load.breakpoints.back(), 0 without breakpoints) for ever, or, given window = {t0, t1}
/// (s), from max(that, t0) to t1.
std::pair<double, double> keptMotionWindow(const PiecewiseConstantLoad& load, const std::vector<double>& window);

/// One completed run's kept motion (motionKeptAfterRelease) and, for a multirate run when
/// at least two backward Euler runs keep some motion, what backward Euler keeps at the
/// same wall time and at the same flops per frame (singleRateAtEqualCost with the kept
/// motion as the error; nullopt where the interpolation has no answer).
struct KeptMotion {
  const BenchmarkRun* run = nullptr;
  double kept = 0.0;
  bool compared = false;  ///< multirate with enough backward Euler runs
  std::optional<EqualCostAnswer> atEqualTime, atEqualFlops;
};
std::vector<KeptMotion> keptMotionComparison(const std::vector<BenchmarkRun>& results, const Trajectory& reference,
                                             const std::vector<double>& times, double release, double until,
                                             int vertex);

/// Band edges (rad/s) for motionKeptPerBand: omega hL in [0, 0.3) and [0.3, 1) are
/// resolved by hL, [1, m) only by the small step hL / m, [m, inf) by neither:
/// {0, 0.3 / hL, 1 / hL, m / hL}. hL in s.
std::vector<double> motionBandEdges(double largeTimestep, int maxRatio);

/// The largest region ratio of any run; 8 when no run has a ratio of 2 or more (so the
/// bands stay meaningful for single-rate lists).
int largestRunRatio(const std::vector<BenchmarkRun>& results);

/// The runs of the equal-cost figure (Figures 4 and 7 of the paper): backward Euler at its
/// largest step (coarse), the completed multirate run with the scene's own ratios and no
/// coupling, schur or method option (else the first completed multirate run), and the
/// backward Euler run other than coarse whose wall time per frame is nearest the multirate
/// run's in log (equalCost). Any of them null when there is no such run.
struct EqualCostFigureRuns {
  const BenchmarkRun* coarse = nullptr;
  const BenchmarkRun* equalCost = nullptr;
  const BenchmarkRun* multirate = nullptr;
};
EqualCostFigureRuns equalCostFigureRuns(const std::vector<BenchmarkRun>& results, const std::vector<int>& sceneRatios);

}  // namespace asyncfem
