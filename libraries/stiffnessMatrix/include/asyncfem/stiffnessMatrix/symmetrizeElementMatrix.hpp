// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>

namespace asyncfem {

/// Replaces entries (i, j) and (j, i) of a 12x12 element matrix by their average. For a
/// matrix that is symmetric in exact arithmetic (the Hessian of an element energy) this
/// removes the rounding asymmetry; the entries are visited in a fixed order.
inline void symmetrizeElementMatrix(ElementMatrix& matrix) {
  for (int j = 0; j < 12; ++j) {
    for (int i = j + 1; i < 12; ++i) {
      const double average = 0.5 * (matrix(i, j) + matrix(j, i));
      matrix(i, j) = average;
      matrix(j, i) = average;
    }
  }
}

}  // namespace asyncfem
