// SPDX-License-Identifier: BSD-3-Clause
// Hexahedral boxes and the cantilever bar shared by the hexElements and problem tests and
// by benchmarkHexahedra.
#pragma once

#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

namespace asyncfem::test {

/// A box [0, size.x] x [0, size.y] x [0, size.z] of cells.x * cells.y * cells.z equal
/// boxes in Vega's vertex order (bottom face counter-clockwise seen from +z, then the
/// top face), one material.
inline TetMesh hexBox(const Eigen::Vector3i& cells, const Eigen::Vector3d& size, const Material& material) {
  const Eigen::Vector3d step = size.cwiseQuotient(cells.cast<double>());
  const auto id = [&](int i, int j, int k) { return i + (cells.x() + 1) * (j + (cells.y() + 1) * k); };
  Eigen::Matrix3Xd x(3, (cells.x() + 1) * (cells.y() + 1) * (cells.z() + 1));
  for (int k = 0; k <= cells.z(); ++k)
    for (int j = 0; j <= cells.y(); ++j)
      for (int i = 0; i <= cells.x(); ++i) x.col(id(i, j, k)) = step.cwiseProduct(Eigen::Vector3d(i, j, k));
  HexElements h(8, cells.prod());
  int e = 0;
  for (int k = 0; k < cells.z(); ++k)
    for (int j = 0; j < cells.y(); ++j)
      for (int i = 0; i < cells.x(); ++i) {
        h.col(e++) << id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k), id(i, j + 1, k), id(i, j, k + 1),
            id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1);
      }
  return TetMesh(x, h, {material}, std::vector<int>(static_cast<std::size_t>(e), 0));
}

/// A bar [0, 1] x [0, 0.25] x [0, 0.25] of (4 n) x n x n cubes in Vega's vertex order.
inline TetMesh hexBar(int n) {
  return hexBox(Eigen::Vector3i(4 * n, n, n), Eigen::Vector3d(1.0, 0.25, 0.25), Material{"bar", 1000.0, 1e6, 0.3});
}

}  // namespace asyncfem::test
