// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <vector>

namespace asyncfem {

/// One measured single-rate configuration: its timestep, its cost per frame (seconds, or
/// flops: any positive measure) and its error.
struct SingleRatePoint {
  double timestep = 0.0;
  double cost = 0.0;
  double error = 0.0;
};

/// A value read off the measured curve; extrapolated when the query lay outside the
/// measured range (the end segment was extended).
struct InterpolatedValue {
  double value = 0.0;
  bool extrapolated = false;
};

/// Piecewise-linear interpolation of log y against log x through the points (x_i, y_i)
/// (all > 0; sorted here by x), evaluated at x: y = y_a (x / x_a)^s on the segment
/// [x_a, x_b] containing x, s = log(y_b / y_a) / log(x_b / x_a); outside [x_min, x_max] the
/// nearest end segment is extended (extrapolated = true). One point: its y (extrapolated
/// unless x equals it). Throws asyncfem::Error with no points or a non-positive value.
InterpolatedValue interpolateLogLog(std::vector<double> x, std::vector<double> y, double at);

/// The x at which the log-log interpolant above takes the value target: the first segment
/// (in ascending x) whose y range contains target is inverted; if none does, the end
/// segment whose y is nearer to target (in log) is extended (extrapolated = true). Throws
/// asyncfem::Error with fewer than one point, a non-positive value, or a flat curve that
/// never reaches target.
InterpolatedValue inverseLogLog(std::vector<double> x, std::vector<double> y, double target);

/// Equal-cost answer for a multirate configuration of cost `cost`: the single-rate timestep
/// of the same cost (inverseLogLog of cost against timestep) and the error interpolated
/// there (interpolateLogLog of error against timestep).
struct EqualCostAnswer {
  double timestep = 0.0;
  double error = 0.0;
  bool extrapolated = false;
};
EqualCostAnswer singleRateAtEqualCost(const std::vector<SingleRatePoint>& singleRate, double cost);

/// Equal-error answer: the single-rate timestep reaching `error` (inverseLogLog of error
/// against timestep) and the cost interpolated there.
struct EqualErrorAnswer {
  double timestep = 0.0;
  double cost = 0.0;
  bool extrapolated = false;
};
EqualErrorAnswer singleRateAtEqualError(const std::vector<SingleRatePoint>& singleRate, double error);

}  // namespace asyncfem
