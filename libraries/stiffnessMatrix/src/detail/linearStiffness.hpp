// SPDX-License-Identifier: BSD-3-Clause
// Internal: the constant-strain element stiffness from precomputed shape-function
// gradients, shared by linearElementStiffness and the assembler's fast path.
#pragma once

#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>

namespace asyncfem::detail {

/// K_e = V B^T C B written block-wise: the 3x3 block coupling vertices a and b is
/// V (lambda g_a g_b^T + mu g_b g_a^T + mu (g_a . g_b) I), the Hessian of
/// V (mu eps:eps + lambda/2 tr(eps)^2) with eps = sym(sum_a u_a g_a^T). lambdaVolume and
/// muVolume are lambda V and mu V. Blocks below the diagonal are copies of those above,
/// and every product is formed as (scalar) * (g_a,i g_b,j), so K_e is exactly symmetric.
inline void linearStiffnessFromGradients(const Eigen::Matrix<double, 3, 4>& g, double lambdaVolume, double muVolume,
                                         ElementMatrix& out) {
  for (int b = 0; b < 4; ++b) {
    for (int a = 0; a <= b; ++a) {
      const double dot = (g(0, a) * g(0, b)) + (g(1, a) * g(1, b)) + (g(2, a) * g(2, b));
      for (int j = 0; j < 3; ++j) {
        for (int i = 0; i < 3; ++i) {
          double value = (lambdaVolume * (g(i, a) * g(j, b))) + (muVolume * (g(i, b) * g(j, a)));
          if (i == j) value += muVolume * dot;
          out((3 * a) + i, (3 * b) + j) = value;
          out((3 * b) + j, (3 * a) + i) = value;
        }
      }
    }
  }
}

}  // namespace asyncfem::detail
