// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Eigenvalues>
#include <asyncfem/barrier/barrier.hpp>
#include <cmath>
#include <limits>

namespace asyncfem {

namespace {

using Vector12 = Eigen::Matrix<double, 12, 1>;
using Matrix12 = Eigen::Matrix<double, 12, 12>;

// E = f(s) for a squared distance s with f's first and second derivatives: E's gradient
// f' grad s and Hessian f'' grad s grad s^T + f' Hess s (the chain rule on 12 coordinates).
SquaredDistance compose(const BarrierDerivatives& f, const SquaredDistance& s) {
  SquaredDistance out;
  out.value = f.value;
  out.gradient = f.first * s.gradient;
  out.hessian = (f.second * s.gradient * s.gradient.transpose()) + (f.first * s.hessian);
  return out;
}

}  // namespace

// Eq. B1 with g = s - sHat and L = ln(s / sHat): b = -g^2 L, b' = -2 g L - g^2 / s,
// b'' = -2 L - 4 g / s + g^2 / s^2.
BarrierDerivatives logBarrier(double s, double sHat) {
  BarrierDerivatives out;
  if (s >= sHat) return out;
  if (!(s > 0.0)) {
    out.value = std::numeric_limits<double>::infinity();
    out.first = out.second = std::numeric_limits<double>::quiet_NaN();
    return out;
  }
  const double gap = s - sHat;
  const double logRatio = std::log(s / sHat);
  out.value = -gap * gap * logRatio;
  out.first = (-2.0 * gap * logRatio) - (gap * gap / s);
  out.second = (-2.0 * logRatio) - (4.0 * gap / s) + (gap * gap / (s * s));
  return out;
}

// Eq. B2: x = |e0|^2 |e1|^2 - (e0.e1)^2. With respect to e0 and e1:
//   dx/de0 = 2 |e1|^2 e0 - 2 (e0.e1) e1,   dx/de1 = 2 |e0|^2 e1 - 2 (e0.e1) e0,
//   d2x/de0^2 = 2 |e1|^2 I - 2 e1 e1^T,     d2x/de1^2 = 2 |e0|^2 I - 2 e0 e0^T,
//   d2x/de0 de1 = 4 e0 e1^T - 2 e1 e0^T - 2 (e0.e1) I;
// a0 and b0 enter their edges with sign -1, a1 and b1 with +1.
SquaredDistance edgeCrossSquared(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& b0,
                                 const Eigen::Vector3d& b1) {
  const Eigen::Vector3d e0 = a1 - a0, e1 = b1 - b0;
  const double n0 = e0.squaredNorm(), n1 = e1.squaredNorm(), dot = e0.dot(e1);
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d g0 = (2.0 * n1 * e0) - (2.0 * dot * e1);
  const Eigen::Vector3d g1 = (2.0 * n0 * e1) - (2.0 * dot * e0);
  Eigen::Matrix3d blocks[2][2];
  blocks[0][0] = (2.0 * n1 * identity) - (2.0 * e1 * e1.transpose());
  blocks[1][1] = (2.0 * n0 * identity) - (2.0 * e0 * e0.transpose());
  blocks[0][1] = (4.0 * e0 * e1.transpose()) - (2.0 * e1 * e0.transpose()) - (2.0 * dot * identity);
  blocks[1][0] = blocks[0][1].transpose();
  const int edgeOf[4] = {0, 0, 1, 1};
  const double sign[4] = {-1.0, 1.0, -1.0, 1.0};
  SquaredDistance out;
  out.value = (n0 * n1) - (dot * dot);
  for (int i = 0; i < 4; ++i) {
    out.gradient.segment<3>(3 * i) = sign[i] * (edgeOf[i] == 0 ? g0 : g1);
    for (int j = 0; j < 4; ++j)
      out.hessian.block<3, 3>(3 * i, 3 * j) = sign[i] * sign[j] * blocks[edgeOf[i]][edgeOf[j]];
  }
  return out;
}

double mollifierThreshold(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& b0,
                          const Eigen::Vector3d& b1) {
  return 1e-3 * (a1 - a0).squaredNorm() * (b1 - b0).squaredNorm();
}

SquaredDistance pointTriangleBarrier(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                     const Eigen::Vector3d& c, double sHat) {
  if (pointTriangleDistanceSquared(p, a, b, c) >= sHat) return {};
  const SquaredDistance s = pointTriangleDistance(p, a, b, c);
  return compose(logBarrier(s.value, sHat), s);
}

// Eq. B3: m(x) = (2 - x / epsX) x / epsX below epsX, 1 above; E = m(x) b(s) by the product rule.
SquaredDistance edgeEdgeBarrier(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& b0,
                                const Eigen::Vector3d& b1, double sHat, double epsX) {
  if (edgeEdgeDistanceSquared(a0, a1, b0, b1) >= sHat) return {};
  const SquaredDistance barrier =
      compose(logBarrier(edgeEdgeDistance(a0, a1, b0, b1).value, sHat), edgeEdgeDistance(a0, a1, b0, b1));
  const SquaredDistance x = edgeCrossSquared(a0, a1, b0, b1);
  if (x.value >= epsX) return barrier;
  BarrierDerivatives m;
  m.value = (2.0 - (x.value / epsX)) * x.value / epsX;
  m.first = (2.0 / epsX) - (2.0 * x.value / (epsX * epsX));
  m.second = -2.0 / (epsX * epsX);
  const SquaredDistance mollifier = compose(m, x);
  SquaredDistance out;
  out.value = mollifier.value * barrier.value;
  out.gradient = (mollifier.value * barrier.gradient) + (barrier.value * mollifier.gradient);
  out.hessian = (mollifier.value * barrier.hessian) + (mollifier.gradient * barrier.gradient.transpose()) +
                (barrier.gradient * mollifier.gradient.transpose()) + (barrier.value * mollifier.hessian);
  return out;
}

Matrix12 projectToPositiveSemiDefinite(const Matrix12& hessian) {
  const Eigen::SelfAdjointEigenSolver<Matrix12> eigen(0.5 * (hessian + hessian.transpose()));
  const Vector12 clamped = eigen.eigenvalues().cwiseMax(0.0);
  return eigen.eigenvectors() * clamped.asDiagonal() * eigen.eigenvectors().transpose();
}

}  // namespace asyncfem
