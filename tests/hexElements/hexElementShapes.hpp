// SPDX-License-Identifier: BSD-3-Clause
// The hexahedron the element-kernel tests evaluate: a 0.5 x 0.4 x 0.3 box with one vertex
// moved (not a parallelepiped), and its material.
#pragma once

#include <Eigen/Core>
#include <asyncfem/hexElements/hexElementMatrices.hpp>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <type_traits>

namespace asyncfem::test {

constexpr double kHexYoung = 1e6;
constexpr double kHexPoisson = 0.35;

inline HexElementPositions hexRestShape() {
  HexElementPositions x;
  for (int a = 0; a < 8; ++a) {
    const auto& c = hexahedron::kCorners[static_cast<std::size_t>(a)];
    x.col(a) = Eigen::Vector3d(0.5 * (c[0] + 1), 0.4 * (c[1] + 1), 0.3 * (c[2] + 1));
  }
  x.col(6) += Eigen::Vector3d(0.1, -0.05, 0.08);  // not a parallelepiped
  return x;
}

/// Central differences (step h) of value(x) over the 24 coordinates of x: column k is
/// d value / d x_k (value returns a scalar or a vector).
template <typename Value>
auto centralDifferences(const HexElementPositions& x, double h, const Value& value) {
  using Result = decltype(value(x));
  Eigen::Matrix<double, Eigen::Dynamic, 24> out;
  for (int k = 0; k < 24; ++k) {
    HexElementPositions plus = x, minus = x;
    plus(k % 3, k / 3) += h;
    minus(k % 3, k / 3) -= h;
    const Result difference = (value(plus) - value(minus)) / (2.0 * h);
    if constexpr (std::is_arithmetic_v<Result>) {
      out.resize(1, 24);
      out(0, k) = difference;
    } else {
      out.resize(difference.size(), 24);
      out.col(k) = difference;
    }
  }
  return out;
}

}  // namespace asyncfem::test
