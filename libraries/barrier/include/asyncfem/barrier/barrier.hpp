// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/collision/distance.hpp>

// The log barrier of incremental potential contact on the squared distances of surface
// primitives (docs/collision.md, "Barrier and continuous collision detection", Eqs. B1-B4).
namespace asyncfem {

/// The barrier b(s) of a squared distance s below the squared activation distance sHat
/// (Eq. B1): b(s) = -(s - sHat)^2 ln(s / sHat) for 0 < s < sHat, 0 for s >= sHat, and its
/// first and second derivatives with respect to s. b and b' vanish at sHat, b grows without
/// bound as s -> 0 (s <= 0 gives +infinity with NaN derivatives: an intersecting pair).
struct BarrierDerivatives {
  double value = 0.0;
  double first = 0.0;
  double second = 0.0;
};
BarrierDerivatives logBarrier(double s, double sHat);

/// x = |e0 x e1|^2 for e0 = a1 - a0, e1 = b1 - b0 (Eq. B2: zero for parallel edges), with
/// its gradient and Hessian with respect to (a0, a1, b0, b1), stacked as in SquaredDistance.
SquaredDistance edgeCrossSquared(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& b0,
                                 const Eigen::Vector3d& b1);

/// The threshold of the edge-edge mollifier from the rest positions (Eq. B3):
/// epsX = 1e-3 |a1 - a0|^2 |b1 - b0|^2.
double mollifierThreshold(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& b0,
                          const Eigen::Vector3d& b1);

/// The barrier energy of one primitive pair and its gradient and Hessian with respect to
/// the pair's 12 coordinates (stacked as in SquaredDistance). Point-triangle: b(s) with s
/// the squared distance in the region pointTriangleRegion finds; edge-edge: m(x) b(s) with
/// the mollifier m of Eq. B3 (smooth where the edges turn parallel, where the closest-point
/// region switches between the interior and an endpoint form). Zero with zero derivatives
/// at s >= sHat.
SquaredDistance pointTriangleBarrier(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                     const Eigen::Vector3d& c, double sHat);
SquaredDistance edgeEdgeBarrier(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& b0,
                                const Eigen::Vector3d& b1, double sHat, double epsX);

/// The nearest symmetric positive semi-definite matrix (negative eigenvalues set to zero):
/// the projected Hessian a Newton step on the incremental potential needs (Eq. B4).
Eigen::Matrix<double, 12, 12> projectToPositiveSemiDefinite(const Eigen::Matrix<double, 12, 12>& hessian);

}  // namespace asyncfem
