// SPDX-License-Identifier: BSD-3-Clause
// hexahedronMaxFrequency() and the region proposal's other measures of hexahedra.
#include "detail/hexahedronFrequency.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <asyncfem/asyncIntegrator/regionProposal.hpp>
#include <asyncfem/hexElements/hexElementMatrices.hpp>
#include <cmath>
#include <utility>

namespace asyncfem {

namespace detail {

Eigen::Matrix<double, 3, 8> unitCube() {
  Eigen::Matrix<double, 3, 8> x;
  x << 0, 1, 1, 0, 0, 1, 1, 0,  //
      0, 0, 1, 1, 0, 0, 1, 1,   //
      0, 0, 0, 0, 1, 1, 1, 1;
  return x;
}

double rmsEdgeLength(const Eigen::Matrix<double, 3, 8>& restPositions) {
  // The bottom face 0-1-2-3, the top face 4-5-6-7 and the four vertical edges a, a + 4.
  static constexpr std::array<std::pair<int, int>, 12> kEdges{
      {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6}, {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}}};
  double sum = 0.0;
  for (const auto& [a, b] : kEdges) sum += (restPositions.col(a) - restPositions.col(b)).squaredNorm();
  return std::sqrt(sum / 12.0);
}

}  // namespace detail

double hexahedronMaxFrequency(const Eigen::Matrix<double, 3, 8>& restPositions, const Material& material) {
  // With the lumped (diagonal, positive) mass D, K v = lambda D v has the eigenvalues of the
  // symmetric D^{-1/2} K D^{-1/2}.
  const HexElementMatrix stiffness = hexLinearStiffness(restPositions, material.youngsModulus, material.poissonRatio);
  const Eigen::Matrix<double, 24, 1> scale =
      hexLumpedMass(restPositions, material.density).diagonal().cwiseSqrt().cwiseInverse();
  const HexElementMatrix scaled = scale.asDiagonal() * stiffness * scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<HexElementMatrix> eigen(scaled, Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, eigen.eigenvalues().maxCoeff()));
}

}  // namespace asyncfem
