// SPDX-License-Identifier: BSD-3-Clause
// A hexahedral cantilever bar shared by the hexElements and problem tests.
#pragma once

#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

namespace asyncfem::test {

/// A bar [0, 1] x [0, 0.25] x [0, 0.25] of (4 n) x n x n cubes in Vega's vertex order.
inline TetMesh hexBar(int n) {
  const int nx = 4 * n;
  const double side = 0.25 / n;
  const auto id = [&](int i, int j, int k) { return i + (nx + 1) * (j + (n + 1) * k); };
  Eigen::Matrix3Xd x(3, (nx + 1) * (n + 1) * (n + 1));
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= nx; ++i) x.col(id(i, j, k)) = side * Eigen::Vector3d(i, j, k);
  HexElements h(8, nx * n * n);
  int e = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < nx; ++i) {
        h.col(e++) << id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k), id(i, j + 1, k), id(i, j, k + 1),
            id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1);
      }
  return TetMesh(x, h, {Material{"bar", 1000.0, 1e6, 0.3}}, std::vector<int>(static_cast<std::size_t>(e), 0));
}

}  // namespace asyncfem::test
