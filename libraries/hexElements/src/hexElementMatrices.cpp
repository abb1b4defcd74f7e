// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Dense>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexElementMatrices.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <string>

namespace asyncfem {

Eigen::Matrix<double, 3, 8> hexShapeGradients(const HexElementPositions& restPositions, const Eigen::Vector3d& xi,
                                              double* jacobianDeterminant) {
  const Eigen::Matrix<double, 8, 3> referenceGradients = hexahedron::shapeFunctionDerivatives(xi);
  const Eigen::Matrix3d jacobian = restPositions * referenceGradients;
  const double det = jacobian.determinant();
  if (jacobianDeterminant != nullptr) *jacobianDeterminant = det;
  // dN/dX = J^-T dN/dxi, column a.
  return jacobian.transpose().partialPivLu().solve(referenceGradients.transpose());
}

Eigen::Matrix<double, 6, 24> hexStrainDisplacement(const Eigen::Matrix<double, 3, 8>& shapeGradients) {
  Eigen::Matrix<double, 6, 24> b = Eigen::Matrix<double, 6, 24>::Zero();
  for (int a = 0; a < 8; ++a) {
    const double gx = shapeGradients(0, a);
    const double gy = shapeGradients(1, a);
    const double gz = shapeGradients(2, a);
    const int c = 3 * a;
    b(0, c) = gx;
    b(1, c + 1) = gy;
    b(2, c + 2) = gz;
    b(3, c + 1) = gz;
    b(3, c + 2) = gy;
    b(4, c) = gz;
    b(4, c + 2) = gx;
    b(5, c) = gy;
    b(5, c + 1) = gx;
  }
  return b;
}

namespace {

/// The isotropic elasticity matrix in the Voigt order of hexStrainDisplacement.
Eigen::Matrix<double, 6, 6> elasticityMatrix(double youngsModulus, double poissonRatio) {
  const Eigen::Vector2d lame = lameParameters(youngsModulus, poissonRatio);
  Eigen::Matrix<double, 6, 6> c = Eigen::Matrix<double, 6, 6>::Zero();
  c.topLeftCorner<3, 3>().setConstant(lame[0]);
  c.topLeftCorner<3, 3>().diagonal().array() += 2.0 * lame[1];
  c.bottomRightCorner<3, 3>().diagonal().setConstant(lame[1]);
  return c;
}

/// det J at Gauss point g, checked to be positive.
void checkJacobian(double det, int g, const char* caller) {
  if (!(det > 0.0)) {
    throw ValidationError(std::string(caller) + ": det J = " + std::to_string(det) + " at Gauss point " +
                          std::to_string(g) + ": the hexahedron is inverted or degenerate");
  }
}

}  // namespace

Eigen::Matrix<double, 24, 24> hexLinearStiffness(const HexElementPositions& restPositions, double youngsModulus,
                                                 double poissonRatio) {
  const Eigen::Matrix<double, 6, 6> c = elasticityMatrix(youngsModulus, poissonRatio);
  HexElementMatrix k = HexElementMatrix::Zero();
  for (int g = 0; g < 8; ++g) {
    double det = 0.0;
    const Eigen::Matrix<double, 6, 24> b =
        hexStrainDisplacement(hexShapeGradients(restPositions, hexahedron::gaussPoint(g), &det));
    checkJacobian(det, g, "hexLinearStiffness");
    k.noalias() += det * (b.transpose() * (c * b));
  }
  // Exact symmetry (the sum above is symmetric up to rounding only).
  return 0.5 * (k + k.transpose());
}

Eigen::Matrix<double, 24, 24> hexConsistentMass(const HexElementPositions& restPositions, double density) {
  Eigen::Matrix<double, 8, 8> scalar = Eigen::Matrix<double, 8, 8>::Zero();
  for (int g = 0; g < 8; ++g) {
    const Eigen::Vector3d xi = hexahedron::gaussPoint(g);
    const double det = hexahedron::jacobian(restPositions, xi).determinant();
    checkJacobian(det, g, "hexConsistentMass");
    const Eigen::Matrix<double, 8, 1> n = hexahedron::shapeFunctions(xi);
    scalar.noalias() += (density * det) * (n * n.transpose());
  }
  HexElementMatrix m = HexElementMatrix::Zero();
  for (int a = 0; a < 8; ++a)
    for (int b = 0; b < 8; ++b)
      for (int c = 0; c < 3; ++c) m((3 * a) + c, (3 * b) + c) = scalar(a, b);
  return m;
}

Eigen::Matrix<double, 24, 24> hexLumpedMass(const HexElementPositions& restPositions, double density) {
  const HexElementMatrix consistent = hexConsistentMass(restPositions, density);
  HexElementMatrix m = HexElementMatrix::Zero();
  m.diagonal() = consistent.rowwise().sum();
  return m;
}

HexGaussPoints hexGaussPoints(const HexElementPositions& restPositions) {
  HexGaussPoints points;
  for (int g = 0; g < 8; ++g) {
    double volume = 0.0;
    points.gradients[static_cast<std::size_t>(g)] =
        hexShapeGradients(restPositions, hexahedron::gaussPoint(g), &volume);
    if (!(volume > 0.0)) {
      throw ValidationError("det J = " + std::to_string(volume) + " at Gauss point " + std::to_string(g) +
                            " of the rest shape: the hexahedron is inverted or degenerate");
    }
    points.volumes[static_cast<std::size_t>(g)] = volume;
  }
  return points;
}

}  // namespace asyncfem
