// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Geometry>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <cmath>
#include <sstream>

#include "detail/linearStiffness.hpp"

namespace asyncfem {

Eigen::Vector2d lameParameters(double youngsModulus, double poissonRatio) {
  const double lambda = youngsModulus * poissonRatio / ((1.0 + poissonRatio) * (1.0 - 2.0 * poissonRatio));
  const double mu = youngsModulus / (2.0 * (1.0 + poissonRatio));
  return {lambda, mu};
}

Eigen::Matrix<double, 3, 4> shapeFunctionGradients(const ElementPositions& restPositions, double* signedVolume) {
  // Edge matrix D = [x1-x0, x2-x0, x3-x0]; the barycentric coordinates (N1, N2, N3) are
  // D^{-1} (x - x0), so grad N_k is row k of D^{-1} and grad N0 = -(sum of the others).
  Eigen::Matrix3d edges;
  edges.col(0) = restPositions.col(1) - restPositions.col(0);
  edges.col(1) = restPositions.col(2) - restPositions.col(0);
  edges.col(2) = restPositions.col(3) - restPositions.col(0);
  // Rows of D^{-1} are the cross products of pairs of columns divided by det D.
  const Eigen::Vector3d c12 = edges.col(1).cross(edges.col(2));
  const Eigen::Vector3d c20 = edges.col(2).cross(edges.col(0));
  const Eigen::Vector3d c01 = edges.col(0).cross(edges.col(1));
  const double determinant = edges.col(0).dot(c12);
  if (signedVolume != nullptr) *signedVolume = determinant / 6.0;
  const double inverseDeterminant = 1.0 / determinant;
  Eigen::Matrix<double, 3, 4> gradients;
  gradients.col(1) = c12 * inverseDeterminant;
  gradients.col(2) = c20 * inverseDeterminant;
  gradients.col(3) = c01 * inverseDeterminant;
  gradients.col(0) = -(gradients.col(1) + gradients.col(2) + gradients.col(3));
  return gradients;
}

ElementMatrix linearElementStiffness(const ElementPositions& restPositions, double youngsModulus, double poissonRatio) {
  double signedVolume = 0.0;
  const Eigen::Matrix<double, 3, 4> g = shapeFunctionGradients(restPositions, &signedVolume);
  const Eigen::Vector2d lame = lameParameters(youngsModulus, poissonRatio);
  // The gradients do not depend on the vertex order; the volume is its absolute value so
  // that an inverted vertex order still gives the positive semi-definite stiffness.
  const double volume = std::abs(signedVolume);
  ElementMatrix k;
  detail::linearStiffnessFromGradients(g, lame[0] * volume, lame[1] * volume, k);
  return k;
}

ElementMatrix consistentElementMass(double volume, double density) {
  const double offDiagonal = density * std::abs(volume) / 20.0;
  ElementMatrix m = ElementMatrix::Zero();
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) {
      const double value = a == b ? 2.0 * offDiagonal : offDiagonal;
      for (int c = 0; c < 3; ++c) m(3 * a + c, 3 * b + c) = value;
    }
  }
  return m;
}

ElementMatrix lumpedElementMass(double volume, double density) {
  ElementMatrix m = ElementMatrix::Zero();
  m.diagonal().setConstant(density * std::abs(volume) / 4.0);
  return m;
}

double longestEdge(const ElementPositions& positions) {
  double longestSquared = 0.0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b)
      longestSquared = std::max(longestSquared, (positions.col(a) - positions.col(b)).squaredNorm());
  return std::sqrt(longestSquared);
}

void checkElementVolume(int element, double signedVolume, double longestEdge, const char* caller) {
  if (std::abs(signedVolume) > 1e-14 * longestEdge * longestEdge * longestEdge && std::isfinite(signedVolume)) return;
  std::ostringstream message;
  if (caller != nullptr) message << caller << ": ";
  message << "element " << element << " is degenerate (signed volume " << signedVolume << ", longest edge "
          << longestEdge << ")";
  throw ValidationError(message.str());
}

}  // namespace asyncfem
