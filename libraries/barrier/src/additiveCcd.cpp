// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/barrier/additiveCcd.hpp>
#include <asyncfem/collision/distance.hpp>
#include <asyncfem/core/error.hpp>
#include <cmath>

namespace asyncfem {

namespace {

using Points = Eigen::Matrix<double, 3, 4>;

// Eq. B5 (conservative advancement on the relative motion). Removing the mean displacement
// leaves every distance between the primitives unchanged along the step; then the distance
// can shrink at most at `speed` per unit time (the largest approach of the first primitive's
// points plus the second's), so an advance of gap / speed never reaches contact. Each
// advance takes 0.9 of that (the first (1 - gapFraction)), and the query stops once the gap
// falls below gapFraction of its start, reporting the last time whose gap was above it.
template <class Distance>
TimeOfImpact advance(const Points& start, const Points& displacement, const AdditiveCcdOptions& options, int firstCount,
                     Distance&& distanceSquared) {
  if (!(options.gapFraction > 0.0 && options.gapFraction < 1.0) || !(options.minimumSeparation >= 0.0)) {
    throw ValidationError("continuous collision detection: gapFraction must be in (0, 1) and minimumSeparation >= 0");
  }
  if (!start.allFinite() || !displacement.allFinite()) {
    throw NumericalError("continuous collision detection: a position or displacement is not finite");
  }
  const Eigen::Vector3d mean = displacement.rowwise().mean();
  const Points relative = displacement.colwise() - mean;
  double first = 0.0, second = 0.0;
  for (int k = 0; k < 4; ++k) {
    double& largest = k < firstCount ? first : second;
    largest = std::max(largest, relative.col(k).norm());
  }
  const double speed = first + second;
  const double xi = options.minimumSeparation;
  const auto gapAt = [&](const Points& x) {
    const double d2 = distanceSquared(x);
    return (d2 - (xi * xi)) / (std::sqrt(d2) + xi);
  };
  Points x = start;
  double gap = gapAt(x);
  TimeOfImpact out;
  if (!(gap > 0.0)) {
    out.impact = true;
    out.stepFraction = 0.0;
    return out;
  }
  if (speed == 0.0) return out;  // the distance never changes
  const double floor = options.gapFraction * gap;
  double reached = 0.0;  // fraction of the motion advanced so far
  double step = (1.0 - options.gapFraction) * gap / speed;
  for (out.iterations = 1; out.iterations <= options.maxIterations; ++out.iterations) {
    x += step * relative;
    gap = gapAt(x);
    if (reached > 0.0 && gap < floor) break;
    reached += step;
    if (reached > 1.0) return {false, 1.0, out.iterations};
    step = 0.9 * gap / speed;
  }
  out.impact = true;
  out.stepFraction = reached;
  return out;
}

}  // namespace

TimeOfImpact pointTriangleTimeOfImpact(const Points& start, const Points& displacement,
                                       const AdditiveCcdOptions& options) {
  return advance(start, displacement, options, 1,
                 [](const Points& x) { return pointTriangleDistanceSquared(x.col(0), x.col(1), x.col(2), x.col(3)); });
}

TimeOfImpact edgeEdgeTimeOfImpact(const Points& start, const Points& displacement, const AdditiveCcdOptions& options) {
  return advance(start, displacement, options, 2,
                 [](const Points& x) { return edgeEdgeDistanceSquared(x.col(0), x.col(1), x.col(2), x.col(3)); });
}

}  // namespace asyncfem
