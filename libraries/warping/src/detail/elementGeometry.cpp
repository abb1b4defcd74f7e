// SPDX-License-Identifier: BSD-3-Clause
#include "detail/elementGeometry.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <cmath>
#include <string>

namespace asyncfem::detail {

void elementShapeGradients(const TetMesh& mesh, std::vector<Eigen::Matrix<double, 3, 4>>& gradients,
                           Eigen::VectorXd& volumes) {
  const int numElements = mesh.numElements();
  gradients.resize(static_cast<std::size_t>(numElements));
  volumes.resize(numElements);
  for (int e = 0; e < numElements; ++e) {
    const Eigen::Matrix<double, 3, 4> rest = mesh.elementRestPositions(e);
    double longestEdge = 0.0;
    for (int a = 0; a < 4; ++a) {
      for (int b = a + 1; b < 4; ++b) {
        longestEdge = std::max(longestEdge, (rest.col(a) - rest.col(b)).norm());
      }
    }
    double signedVolume = 0.0;
    const Eigen::Matrix<double, 3, 4> g = shapeFunctionGradients(rest, &signedVolume);
    // Same threshold as the stiffness assembly, so a mesh that simulates also warps.
    if (!(std::abs(signedVolume) > 1e-14 * longestEdge * longestEdge * longestEdge)) {
      throw ValidationError("warping: element " + std::to_string(e) + " is degenerate (volume " +
                            std::to_string(signedVolume) + ")");
    }
    gradients[static_cast<std::size_t>(e)] = g;
    volumes[e] = std::abs(signedVolume);
  }
}

Eigen::Matrix3d rotationFromVector(const Eigen::Vector3d& w) {
  const double t2 = w.squaredNorm();
  const double t = std::sqrt(t2);
  double sinOverT = 0.0;
  double oneMinusCosOverT2 = 0.0;
  if (t < 0.05) {
    // Next terms t^8 / 362880 and t^8 / 3628800 are below 1e-15 relative here.
    sinOverT = 1.0 - t2 / 6.0 + t2 * t2 / 120.0 - t2 * t2 * t2 / 5040.0;
    oneMinusCosOverT2 = 0.5 - t2 / 24.0 + t2 * t2 / 720.0 - t2 * t2 * t2 / 40320.0;
  } else {
    sinOverT = std::sin(t) / t;
    oneMinusCosOverT2 = (1.0 - std::cos(t)) / t2;
  }
  Eigen::Matrix3d cross;
  cross << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return Eigen::Matrix3d::Identity() + sinOverT * cross + oneMinusCosOverT2 * (cross * cross);
}

}  // namespace asyncfem::detail
