// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/benchmarkTools/costInterpolation.hpp>
#include <asyncfem/core/error.hpp>
#include <cmath>
#include <numeric>
#include <string>

namespace asyncfem {

namespace {

struct LogCurve {
  std::vector<double> x, y;  // logs, sorted by x
};

LogCurve logCurve(const std::vector<double>& x, const std::vector<double>& y, const char* caller) {
  if (x.empty() || x.size() != y.size()) {
    throw Error(std::string(caller) + ": need at least one point and as many x as y values");
  }
  std::vector<std::size_t> order(x.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return x[a] < x[b]; });
  LogCurve curve;
  for (const std::size_t i : order) {
    if (!(x[i] > 0.0) || !(y[i] > 0.0) || !std::isfinite(x[i]) || !std::isfinite(y[i])) {
      throw Error(std::string(caller) + ": every value must be positive and finite (log-log interpolation)");
    }
    curve.x.push_back(std::log(x[i]));
    curve.y.push_back(std::log(y[i]));
  }
  return curve;
}

double lerp(double x0, double y0, double x1, double y1, double at) {
  if (x1 == x0) return 0.5 * (y0 + y1);
  return y0 + (y1 - y0) * (at - x0) / (x1 - x0);
}

}  // namespace

InterpolatedValue interpolateLogLog(std::vector<double> x, std::vector<double> y, double at) {
  const LogCurve c = logCurve(x, y, "interpolateLogLog");
  if (!(at > 0.0)) throw Error("interpolateLogLog: the query must be positive");
  const double lx = std::log(at);
  const std::size_t n = c.x.size();
  if (n == 1) return {std::exp(c.y[0]), lx != c.x[0]};
  std::size_t segment = 0;
  while (segment + 2 < n && lx > c.x[segment + 1]) ++segment;
  const bool outside = lx < c.x.front() || lx > c.x.back();
  return {std::exp(lerp(c.x[segment], c.y[segment], c.x[segment + 1], c.y[segment + 1], lx)), outside};
}

InterpolatedValue inverseLogLog(std::vector<double> x, std::vector<double> y, double target) {
  const LogCurve c = logCurve(x, y, "inverseLogLog");
  if (!(target > 0.0)) throw Error("inverseLogLog: the target must be positive");
  const double ly = std::log(target);
  const std::size_t n = c.x.size();
  if (n == 1) return {std::exp(c.x[0]), ly != c.y[0]};
  for (std::size_t s = 0; s + 1 < n; ++s) {
    const double lo = std::min(c.y[s], c.y[s + 1]), hi = std::max(c.y[s], c.y[s + 1]);
    if (ly >= lo && ly <= hi) {
      if (c.y[s] == c.y[s + 1]) return {std::exp(c.x[s]), false};
      return {std::exp(lerp(c.y[s], c.x[s], c.y[s + 1], c.x[s + 1], ly)), false};
    }
  }
  // Outside the measured range: extend the end segment nearer to the target.
  const bool useFirst = std::abs(ly - c.y.front()) <= std::abs(ly - c.y.back());
  const std::size_t s = useFirst ? 0 : n - 2;
  if (c.y[s] == c.y[s + 1]) {
    throw Error("inverseLogLog: the measured curve is flat near its end and never reaches the target");
  }
  return {std::exp(lerp(c.y[s], c.x[s], c.y[s + 1], c.x[s + 1], ly)), true};
}

EqualCostAnswer singleRateAtEqualCost(const std::vector<SingleRatePoint>& singleRate, double cost) {
  std::vector<double> h, costs, errors;
  for (const SingleRatePoint& p : singleRate) {
    h.push_back(p.timestep);
    costs.push_back(p.cost);
    errors.push_back(p.error);
  }
  const InterpolatedValue step = inverseLogLog(h, costs, cost);
  const InterpolatedValue error = interpolateLogLog(h, errors, step.value);
  return {step.value, error.value, step.extrapolated || error.extrapolated};
}

EqualErrorAnswer singleRateAtEqualError(const std::vector<SingleRatePoint>& singleRate, double error) {
  std::vector<double> h, costs, errors;
  for (const SingleRatePoint& p : singleRate) {
    h.push_back(p.timestep);
    costs.push_back(p.cost);
    errors.push_back(p.error);
  }
  const InterpolatedValue step = inverseLogLog(h, errors, error);
  const InterpolatedValue cost = interpolateLogLog(h, costs, step.value);
  return {step.value, cost.value, step.extrapolated || cost.extrapolated};
}

}  // namespace asyncfem
