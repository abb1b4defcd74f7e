// SPDX-License-Identifier: BSD-3-Clause
// Equal-cost and equal-error interpolation on synthetic power laws.
#include <gtest/gtest.h>

#include <asyncfem/benchmarkTools/costInterpolation.hpp>
#include <asyncfem/core/error.hpp>
#include <cmath>

namespace asyncfem {
namespace {

// Single-rate points following cost = 1e-3 / h and error = 50 h exactly: log-log
// interpolation reproduces power laws exactly, so answers are exact to round-off (1e-12).
std::vector<SingleRatePoint> powerLaw() {
  std::vector<SingleRatePoint> points;
  for (const double h : {1e-3, 2e-3, 4e-3, 8e-3}) points.push_back({h, 1e-3 / h, 50.0 * h});
  return points;
}

TEST(CostInterpolation, PowerLawsAreReproducedExactly) {
  const InterpolatedValue y = interpolateLogLog({1, 10, 100}, {3, 30, 300}, 42.0);
  EXPECT_NEAR(y.value, 126.0, 1e-12 * 126.0);
  EXPECT_FALSE(y.extrapolated);
  const InterpolatedValue x = inverseLogLog({1, 10, 100}, {3, 30, 300}, 126.0);
  EXPECT_NEAR(x.value, 42.0, 1e-12 * 42.0);
}

TEST(CostInterpolation, EqualCostAndEqualErrorOnSyntheticData) {
  // A multirate run costing 0.7 s per frame: the single-rate step of equal cost is
  // 1e-3 / 0.7, its error 50 h.
  const EqualCostAnswer cost = singleRateAtEqualCost(powerLaw(), 0.7);
  EXPECT_NEAR(cost.timestep, 1e-3 / 0.7, 1e-12);
  EXPECT_NEAR(cost.error, 50.0 * 1e-3 / 0.7, 1e-12);
  EXPECT_FALSE(cost.extrapolated);
  // Reaching error 0.09 needs h = 1.8e-3, costing 1e-3 / 1.8e-3.
  const EqualErrorAnswer error = singleRateAtEqualError(powerLaw(), 0.09);
  EXPECT_NEAR(error.timestep, 1.8e-3, 1e-15);
  EXPECT_NEAR(error.cost, 1e-3 / 1.8e-3, 1e-12);
  EXPECT_FALSE(error.extrapolated);
}

TEST(CostInterpolation, OutsideTheMeasuredRangeIsFlaggedExtrapolated) {
  const EqualErrorAnswer error = singleRateAtEqualError(powerLaw(), 0.01);  // needs h = 2e-4
  EXPECT_TRUE(error.extrapolated);
  EXPECT_NEAR(error.timestep, 2e-4, 1e-15);
  EXPECT_NEAR(error.cost, 5.0, 1e-10);
}

TEST(CostInterpolation, RejectsNonPositiveValues) {
  EXPECT_THROW(interpolateLogLog({1, 2}, {1, 0}, 1.5), Error);
  EXPECT_THROW(inverseLogLog({}, {}, 1.0), Error);
  EXPECT_THROW(inverseLogLog({1, 2}, {3, 3}, 5.0), Error);  // flat: never reaches 5
}

}  // namespace
}  // namespace asyncfem
