// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>

// Continuous collision detection for a line search that must never let a surface cross
// another (docs/collision.md, "Barrier and continuous collision detection", Eq. B5).
namespace asyncfem {

/// What a time-of-impact query found. `impact` false: the pair stays apart (above
/// `minimumSeparation`) over the whole step, certified. `impact` true: the step is cut at
/// `stepFraction` in [0, 1] (a fraction of the motion given, not a clock time), no later
/// than the first contact if there is one, where the pair is still apart; the query stops
/// once the gap has fallen below `gapFraction` of its start, so a pair that only comes
/// close (a point grazing a face) is cut too, and a line search queries again from there.
struct TimeOfImpact {
  bool impact = false;
  double stepFraction = 1.0;
  int iterations = 0;
};

struct AdditiveCcdOptions {
  /// The fraction of the start gap (the squared distance minus the minimum separation's
  /// square, over the distance plus the separation) a reported time keeps: 0.1 stops at
  /// 90% of the way to contact at the latest. In (0, 1).
  double gapFraction = 0.1;
  /// Distances (not squared) below which primitives count as touching; 0 for contact.
  double minimumSeparation = 0.0;
  /// Stop after this many advancement steps and report the time reached so far (still
  /// safe: every advancement is conservative).
  int maxIterations = 1000000;
};

/// Point-triangle: p, a, b, c move linearly from x0 to x0 + displacement over the step
/// (each a 3 x 4 matrix, columns p, a, b, c). Conservative advancement on the relative
/// motion (the mean displacement removed): each advance is the gap over the largest
/// possible approach speed, so the reported time never passes the first contact.
TimeOfImpact pointTriangleTimeOfImpact(const Eigen::Matrix<double, 3, 4>& start,
                                       const Eigen::Matrix<double, 3, 4>& displacement,
                                       const AdditiveCcdOptions& options = {});
/// Edge-edge: columns a0, a1, b0, b1.
TimeOfImpact edgeEdgeTimeOfImpact(const Eigen::Matrix<double, 3, 4>& start,
                                  const Eigen::Matrix<double, 3, 4>& displacement,
                                  const AdditiveCcdOptions& options = {});

}  // namespace asyncfem
