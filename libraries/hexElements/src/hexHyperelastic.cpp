// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexHyperelastic.hpp>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <string>

namespace asyncfem {

namespace {

/// Adds volume G^T (dP/dF) G to tangent, per 3 x 3 block pair (c, d) of coordinates.
void addGaussPointTangent(const Eigen::Matrix<double, 9, 9>& stressDerivative,
                          const Eigen::Matrix<double, 3, 8>& gradients, double volume, HexElementMatrix& tangent) {
  const Eigen::Matrix<double, 3, 8> scaled = volume * gradients;
  for (int c = 0; c < 3; ++c) {
    for (int d = 0; d < 3; ++d) {
      const Eigen::Matrix<double, 3, 8> right = stressDerivative.block<3, 3>(3 * c, 3 * d) * gradients;
      const Eigen::Matrix<double, 8, 8> block = scaled.transpose() * right;
      for (int a = 0; a < 8; ++a)
        for (int b = 0; b < 8; ++b) tangent((3 * a) + c, (3 * b) + d) += block(a, b);
    }
  }
}

}  // namespace

HexElementEnergy hexIsotropicHyperelastic(const HexGaussPoints& rest, const HexElementPositions& deformedPositions,
                                          const IsotropicMaterialPoint& material, bool withTangent) {
  HexElementEnergy out;
  out.force.setZero();
  if (withTangent) out.tangent.setZero();
  Eigen::Matrix<double, 9, 9> stressDerivative;
  for (std::size_t g = 0; g < 8; ++g) {
    const Eigen::Matrix<double, 3, 8>& gradients = rest.gradients[g];
    const double volume = rest.volumes[g];
    const Eigen::Matrix3d f = deformedPositions * gradients.transpose();
    double density = 0.0;
    Eigen::Matrix3d stress;
    material.evaluate(f, &density, &stress, withTangent ? &stressDerivative : nullptr);
    out.energy += volume * density;
    const Eigen::Matrix<double, 3, 8> nodal = volume * (stress * gradients);
    out.force += Eigen::Map<const HexElementVector>(nodal.data());
    if (withTangent) addGaussPointTangent(stressDerivative, gradients, volume, out.tangent);
  }
  if (withTangent) out.tangent = 0.5 * (out.tangent + out.tangent.transpose());
  return out;
}

HexElementEnergy hexIsotropicHyperelastic(const HexElementPositions& restPositions,
                                          const HexElementPositions& deformedPositions,
                                          const IsotropicMaterialPoint& material, bool withTangent) {
  return hexIsotropicHyperelastic(hexGaussPoints(restPositions), deformedPositions, material, withTangent);
}

}  // namespace asyncfem
