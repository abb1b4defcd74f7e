// SPDX-License-Identifier: BSD-3-Clause
// A sparse SPD test matrix shared by the sparse solver tests.
#pragma once

#include <Eigen/SparseCore>
#include <vector>

namespace asyncfem::test {

/// 3D grid Laplacian (7-point stencil, Dirichlet boundary) plus shift * I: SPD, n = k^3,
/// eigenvalues in (shift, 12 + shift).
inline Eigen::SparseMatrix<double> gridLaplacian(int k, double shift) {
  const int n = k * k * k;
  std::vector<Eigen::Triplet<double>> triplets;
  auto id = [k](int i, int j, int l) { return i + k * (j + k * l); };
  for (int l = 0; l < k; ++l)
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < k; ++i) {
        const int row = id(i, j, l);
        triplets.emplace_back(row, row, 6.0 + shift);
        if (i > 0) triplets.emplace_back(row, id(i - 1, j, l), -1.0);
        if (i + 1 < k) triplets.emplace_back(row, id(i + 1, j, l), -1.0);
        if (j > 0) triplets.emplace_back(row, id(i, j - 1, l), -1.0);
        if (j + 1 < k) triplets.emplace_back(row, id(i, j + 1, l), -1.0);
        if (l > 0) triplets.emplace_back(row, id(i, j, l - 1), -1.0);
        if (l + 1 < k) triplets.emplace_back(row, id(i, j, l + 1), -1.0);
      }
  Eigen::SparseMatrix<double> a(n, n);
  a.setFromTriplets(triplets.begin(), triplets.end());
  a.makeCompressed();
  return a;
}

}  // namespace asyncfem::test
