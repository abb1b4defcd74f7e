// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Dense>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <cmath>
#include <limits>

namespace asyncfem::hexahedron {

int flippedCorner(int a, int mask) {
  std::array<int, 3> target = kCorners[static_cast<std::size_t>(a)];
  for (std::size_t axis = 0; axis < 3; ++axis) {
    if ((mask >> axis) & 1) target[axis] = -target[axis];
  }
  for (int b = 0; b < 8; ++b) {
    if (kCorners[static_cast<std::size_t>(b)] == target) return b;
  }
  return -1;  // unreachable: every sign pattern is a corner
}

Eigen::Matrix<double, 8, 1> shapeFunctions(const Eigen::Vector3d& xi) {
  Eigen::Matrix<double, 8, 1> n;
  for (int a = 0; a < 8; ++a) {
    const auto& c = kCorners[static_cast<std::size_t>(a)];
    n[a] = (1.0 + xi[0] * c[0]) * (1.0 + xi[1] * c[1]) * (1.0 + xi[2] * c[2]) / 8.0;
  }
  return n;
}

Eigen::Matrix<double, 8, 3> shapeFunctionDerivatives(const Eigen::Vector3d& xi) {
  Eigen::Matrix<double, 8, 3> dn;
  for (int a = 0; a < 8; ++a) {
    const auto& c = kCorners[static_cast<std::size_t>(a)];
    const double fx = 1.0 + xi[0] * c[0];
    const double fy = 1.0 + xi[1] * c[1];
    const double fz = 1.0 + xi[2] * c[2];
    dn(a, 0) = c[0] * fy * fz / 8.0;
    dn(a, 1) = fx * c[1] * fz / 8.0;
    dn(a, 2) = fx * fy * c[2] / 8.0;
  }
  return dn;
}

Eigen::Matrix3d jacobian(const Eigen::Matrix<double, 3, 8>& x, const Eigen::Vector3d& xi) {
  return x * shapeFunctionDerivatives(xi);
}

Eigen::Vector3d referenceCoordinates(const Eigen::Matrix<double, 3, 8>& x, const Eigen::Vector3d& p, int iterations) {
  Eigen::Vector3d xi = Eigen::Vector3d::Zero();
  for (int i = 0; i < iterations; ++i) {
    const Eigen::Vector3d residual = x * shapeFunctions(xi) - p;
    const Eigen::Vector3d step = jacobian(x, xi).partialPivLu().solve(residual);
    if (!step.allFinite()) break;  // a flat element: keep the last iterate
    xi -= step;
    if (step.lpNorm<Eigen::Infinity>() < 1e-13) break;
  }
  return xi;
}

Eigen::Vector3d gaussPoint(int g) {
  const double p = 1.0 / std::sqrt(3.0);
  const auto& c = kCorners[static_cast<std::size_t>(g)];
  return {p * c[0], p * c[1], p * c[2]};
}

double signedVolume(const Eigen::Matrix<double, 3, 8>& x) {
  double volume = 0.0;
  for (int g = 0; g < 8; ++g) volume += jacobian(x, gaussPoint(g)).determinant();
  return volume;
}

namespace {

/// The three edge vectors leaving vertex a along +xi, +eta, +zeta of the reference cube
/// (towards the neighbour, negated where the neighbour lies on the minus side), i.e.
/// 2 J at that corner.
Eigen::Matrix3d cornerEdges(const Eigen::Matrix<double, 3, 8>& x, int a) {
  Eigen::Matrix3d edges;
  const auto& c = kCorners[static_cast<std::size_t>(a)];
  for (int axis = 0; axis < 3; ++axis) {
    const int neighbour = flippedCorner(a, 1 << axis);
    // The neighbour lies at -c[axis] on this axis: the +axis direction is (neighbour - a)
    // when c[axis] = -1, (a - neighbour) when c[axis] = +1.
    edges.col(axis) = (x.col(neighbour) - x.col(a)) * static_cast<double>(-c[static_cast<std::size_t>(axis)]);
  }
  return edges;
}

}  // namespace

Eigen::Matrix<double, 8, 1> cornerJacobians(const Eigen::Matrix<double, 3, 8>& x) {
  Eigen::Matrix<double, 8, 1> det;
  for (int a = 0; a < 8; ++a) det[a] = cornerEdges(x, a).determinant();
  return det;
}

Eigen::Matrix<double, 8, 1> cornerScaledJacobians(const Eigen::Matrix<double, 3, 8>& x) {
  Eigen::Matrix<double, 8, 1> scaled;
  for (int a = 0; a < 8; ++a) {
    const Eigen::Matrix3d edges = cornerEdges(x, a);
    const double lengths = edges.col(0).norm() * edges.col(1).norm() * edges.col(2).norm();
    scaled[a] = lengths > 0.0 ? edges.determinant() / lengths : std::numeric_limits<double>::quiet_NaN();
  }
  return scaled;
}

}  // namespace asyncfem::hexahedron
