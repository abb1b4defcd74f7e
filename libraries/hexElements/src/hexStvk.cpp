// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Dense>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexStvk.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <string>

namespace asyncfem {

HexStvkElement hexStvk(const HexElementPositions& restPositions, const HexElementPositions& deformedPositions,
                       double youngsModulus, double poissonRatio, bool withTangent) {
  const Eigen::Vector2d lame = lameParameters(youngsModulus, poissonRatio);
  const double lambda = lame[0];
  const double mu = lame[1];
  HexStvkElement out;
  out.force.setZero();
  if (withTangent) out.tangent.setZero();
  for (int g = 0; g < 8; ++g) {
    double volume = 0.0;  // det J of the rest shape: the Gauss weight (1) times the volume ratio
    const Eigen::Matrix<double, 3, 8> gradients = hexShapeGradients(restPositions, hexahedron::gaussPoint(g), &volume);
    if (!(volume > 0.0)) {
      throw ValidationError("hexStvk: det J = " + std::to_string(volume) + " at Gauss point " + std::to_string(g) +
                            " of the rest shape: the hexahedron is inverted or degenerate");
    }
    const Eigen::Matrix3d f = deformedPositions * gradients.transpose();
    const Eigen::Matrix3d green = 0.5 * (f.transpose() * f - Eigen::Matrix3d::Identity());
    const double trace = green.trace();
    const Eigen::Matrix3d second = lambda * trace * Eigen::Matrix3d::Identity() + 2.0 * mu * green;
    out.energy += volume * (0.5 * lambda * trace * trace + mu * green.squaredNorm());
    const Eigen::Matrix3d first = f * second;
    for (int a = 0; a < 8; ++a) out.force.segment<3>(3 * a) += volume * first * gradients.col(a);
    if (!withTangent) continue;
    // Column 3 b + j: dP for dF = e_j grad_b^T, then its action on every grad_a.
    for (int b = 0; b < 8; ++b) {
      for (int j = 0; j < 3; ++j) {
        const Eigen::Matrix3d dF = Eigen::Vector3d::Unit(j) * gradients.col(b).transpose();
        const Eigen::Matrix3d dGreen = 0.5 * (f.transpose() * dF + dF.transpose() * f);
        const Eigen::Matrix3d dSecond = lambda * dGreen.trace() * Eigen::Matrix3d::Identity() + 2.0 * mu * dGreen;
        const Eigen::Matrix3d dFirst = dF * second + f * dSecond;
        for (int a = 0; a < 8; ++a) {
          out.tangent.block<3, 1>(3 * a, (3 * b) + j) += volume * dFirst * gradients.col(a);
        }
      }
    }
  }
  if (withTangent) out.tangent = 0.5 * (out.tangent + out.tangent.transpose());
  return out;
}

}  // namespace asyncfem
