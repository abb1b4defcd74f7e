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
  return hexStvk(hexGaussPoints(restPositions), deformedPositions, lameParameters(youngsModulus, poissonRatio),
                 withTangent);
}

HexStvkElement hexStvk(const HexGaussPoints& rest, const HexElementPositions& deformedPositions,
                       const Eigen::Vector2d& lame, bool withTangent) {
  const double lambda = lame[0];
  const double mu = lame[1];
  HexStvkElement out;
  out.force.setZero();
  if (withTangent) out.tangent.setZero();
  for (std::size_t g = 0; g < 8; ++g) {
    const double volume = rest.volumes[g];  // det J of the rest shape: the Gauss weight (1) times the volume ratio
    const Eigen::Matrix<double, 3, 8>& gradients = rest.gradients[g];
    const Eigen::Matrix3d f = deformedPositions * gradients.transpose();
    const Eigen::Matrix3d green = 0.5 * (f.transpose() * f - Eigen::Matrix3d::Identity());
    const double trace = green.trace();
    const Eigen::Matrix3d second = lambda * trace * Eigen::Matrix3d::Identity() + 2.0 * mu * green;
    out.energy += volume * (0.5 * lambda * trace * trace + mu * green.squaredNorm());
    const Eigen::Matrix3d first = f * second;
    for (int a = 0; a < 8; ++a) out.force.segment<3>(3 * a) += volume * first * gradients.col(a);
    if (!withTangent) continue;
    // dP for dF = e_j g_b^T acting on g_a, with h = F g: block (a, b) of the tangent is
    // (g_a . S g_b) I + lambda h_a h_b^T + mu (g_a . g_b) F F^T + mu h_b h_a^T.
    const Eigen::Matrix<double, 3, 8> deformedGradients = f * gradients;
    const Eigen::Matrix<double, 3, 8> stressed = second * gradients;
    const Eigen::Matrix3d stretch = mu * f * f.transpose();
    for (int b = 0; b < 8; ++b) {
      for (int a = b; a < 8; ++a) {
        const Eigen::Vector3d ha = deformedGradients.col(a), hb = deformedGradients.col(b);
        Eigen::Matrix3d block = (lambda * ha * hb.transpose()) + (mu * hb * ha.transpose()) +
                                (gradients.col(a).dot(gradients.col(b)) * stretch);
        block.diagonal().array() += gradients.col(a).dot(stressed.col(b));
        out.tangent.block<3, 3>(3 * a, 3 * b) += volume * block;
      }
    }
  }
  if (withTangent) {  // the blocks above the diagonal are the transposes of those below
    for (int b = 0; b < 8; ++b)
      for (int a = b + 1; a < 8; ++a)
        out.tangent.block<3, 3>(3 * b, 3 * a) = out.tangent.block<3, 3>(3 * a, 3 * b).transpose();
  }
  return out;
}

}  // namespace asyncfem
