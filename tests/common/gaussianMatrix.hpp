// SPDX-License-Identifier: BSD-3-Clause
// A reproducible dense matrix of standard normal entries, for tests.
#pragma once

#include <Eigen/Core>
#include <random>

namespace asyncfem::test {

/// rows x cols, entries drawn from N(0, 1) by std::mt19937(seed), in storage order.
inline Eigen::MatrixXd gaussianMatrix(Eigen::Index rows, Eigen::Index cols, unsigned seed) {
  std::mt19937 random(seed);
  std::normal_distribution<double> draw;
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index k = 0; k < m.size(); ++k) m.data()[k] = draw(random);
  return m;
}

}  // namespace asyncfem::test
