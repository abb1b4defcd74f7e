// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/benchmarkTools/multirateComparison.hpp>
#include <asyncfem/core/error.hpp>
#include <cmath>
#include <limits>

namespace asyncfem {

std::string toString(CostKind kind) { return kind == CostKind::time ? "time" : "flops"; }

double runCost(const BenchmarkRun& run, CostKind kind) {
  return kind == CostKind::time ? run.medianSecondsPerFrame : run.flopsPerFrame();
}

std::vector<SingleRatePoint> backwardEulerPoints(const std::vector<BenchmarkRun>& results, CostKind kind,
                                                 const std::string& group) {
  std::vector<SingleRatePoint> points;
  for (const BenchmarkRun& r : results) {
    if (r.configuration.integrator != "backward-euler" || !r.completed) continue;
    const double cost = runCost(r, kind);
    const auto it = r.errors.find(group);
    if (it == r.errors.end() || !(cost > 0.0) || !(it->second > 0.0)) continue;
    points.push_back({r.timestep, cost, it->second});
  }
  return points;
}

namespace {

EqualAnswers answerFor(const BenchmarkRun& run, const std::vector<SingleRatePoint>& points, const std::string& group,
                       CostKind kind) {
  EqualAnswers answer;
  answer.run = &run;
  answer.group = group;
  answer.costKind = kind;
  const auto it = run.errors.find(group);
  try {
    if (points.size() < 2) throw Error("fewer than two measured single-rate backward Euler points");
    if (it == run.errors.end()) throw Error("no error for group " + group);
    answer.atEqualCost = singleRateAtEqualCost(points, runCost(run, kind));
    answer.atEqualError = singleRateAtEqualError(points, it->second);
  } catch (const Error& error) {
    answer.problem = error.what();
  }
  return answer;
}

}  // namespace

std::vector<EqualAnswers> equalAnswers(const std::vector<BenchmarkRun>& results,
                                       const std::vector<std::string>& groupNames) {
  std::vector<EqualAnswers> answers;
  for (const std::string& group : groupNames) {
    for (const CostKind kind : {CostKind::time, CostKind::flops}) {
      const std::vector<SingleRatePoint> points = backwardEulerPoints(results, kind, group);
      for (const BenchmarkRun& r : results) {
        if (isMultirate(r.configuration.integrator) && r.completed)
          answers.push_back(answerFor(r, points, group, kind));
      }
    }
  }
  return answers;
}

double motionKeptAfterRelease(const Trajectory& run, const Trajectory& reference, const std::vector<double>& times,
                              double release, double until, int vertex) {
  const auto inWindow = [&](std::size_t k) { return times[k] > release && times[k] <= until; };
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  int count = 0;
  for (std::size_t k = 0; k < reference.size() && k < times.size(); ++k) {
    if (!inWindow(k)) continue;
    centre += reference[k].segment<3>(3 * vertex);
    ++count;
  }
  if (count == 0) return std::numeric_limits<double>::quiet_NaN();
  centre /= count;
  double runSum = 0.0, referenceSum = 0.0;
  for (std::size_t k = 0; k < reference.size() && k < run.size() && k < times.size(); ++k) {
    if (!inWindow(k)) continue;
    runSum += (run[k].segment<3>(3 * vertex) - centre).squaredNorm();
    referenceSum += (reference[k].segment<3>(3 * vertex) - centre).squaredNorm();
  }
  return referenceSum > 0.0 ? std::sqrt(runSum / referenceSum) : std::numeric_limits<double>::quiet_NaN();
}

std::pair<double, double> keptMotionWindow(const PiecewiseConstantLoad& load, const std::vector<double>& window) {
  double release = load.breakpoints.empty() ? 0.0 : load.breakpoints.back();
  double until = std::numeric_limits<double>::infinity();
  if (window.size() == 2) {
    release = std::max(release, window[0]);
    until = window[1];
  }
  return {release, until};
}

namespace {

std::optional<EqualCostAnswer> keptAtEqualCost(const std::vector<SingleRatePoint>& points, double cost) {
  try {
    return singleRateAtEqualCost(points, cost);
  } catch (const Error&) {
    return std::nullopt;
  }
}

}  // namespace

std::vector<KeptMotion> keptMotionComparison(const std::vector<BenchmarkRun>& results, const Trajectory& reference,
                                             const std::vector<double>& times, double release, double until,
                                             int vertex) {
  std::vector<KeptMotion> rows;
  std::vector<SingleRatePoint> byTime, byFlops;  // (timestep, cost, kept) of backward Euler
  for (const BenchmarkRun& r : results) {
    if (!r.completed) continue;
    const double kept = motionKeptAfterRelease(r.frames, reference, times, release, until, vertex);
    rows.push_back({&r, kept, false, std::nullopt, std::nullopt});
    if (r.configuration.integrator == "backward-euler" && kept > 0.0) {
      byTime.push_back({r.timestep, r.medianSecondsPerFrame, kept});
      byFlops.push_back({r.timestep, r.flopsPerFrame(), kept});
    }
  }
  for (KeptMotion& row : rows) {
    if (!isMultirate(row.run->configuration.integrator) || byTime.size() < 2) continue;
    row.compared = true;
    row.atEqualTime = keptAtEqualCost(byTime, row.run->medianSecondsPerFrame);
    row.atEqualFlops = keptAtEqualCost(byFlops, row.run->flopsPerFrame());
  }
  return rows;
}

std::vector<double> motionBandEdges(double largeTimestep, int maxRatio) {
  return {0.0, 0.3 / largeTimestep, 1.0 / largeTimestep, maxRatio / largeTimestep};
}

int largestRunRatio(const std::vector<BenchmarkRun>& results) {
  int largest = 1;
  for (const BenchmarkRun& r : results) {
    for (const int ratio : r.ratios) largest = std::max(largest, ratio);
  }
  return largest < 2 ? 8 : largest;
}

EqualCostFigureRuns equalCostFigureRuns(const std::vector<BenchmarkRun>& results, const std::vector<int>& sceneRatios) {
  EqualCostFigureRuns figure;
  for (const BenchmarkRun& r : results) {
    if (!r.completed || r.frames.empty()) continue;
    const nlohmann::json& options = r.configuration.options;
    if (isMultirate(r.configuration.integrator)) {
      const bool plain = !options.contains("coupling") && !options.contains("schur") && !options.contains("method");
      if (!figure.multirate || (plain && r.ratios == sceneRatios)) figure.multirate = &r;
    } else if (r.configuration.integrator == "backward-euler" &&
               (!figure.coarse || r.timestep > figure.coarse->timestep)) {
      figure.coarse = &r;
    }
  }
  if (!figure.multirate || !figure.coarse) return figure;
  const auto distance = [&](const BenchmarkRun& x) {
    return std::abs(std::log(x.medianSecondsPerFrame / figure.multirate->medianSecondsPerFrame));
  };
  for (const BenchmarkRun& r : results) {
    if (!r.completed || r.frames.empty() || r.configuration.integrator != "backward-euler" || &r == figure.coarse) {
      continue;
    }
    if (!figure.equalCost || distance(r) < distance(*figure.equalCost)) figure.equalCost = &r;
  }
  return figure;
}

}  // namespace asyncfem
