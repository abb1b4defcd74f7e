// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <asyncfem/corotationalLinearFEM/polarDecomposition.hpp>

namespace asyncfem {

PolarDecomposition polarDecomposition(const Eigen::Matrix3d& deformationGradient) {
  // F is square, so the QR preconditioning step of JacobiSVD (meant for rectangular
  // matrices) only costs time: without it the decomposition is about twice as fast.
  const Eigen::JacobiSVD<Eigen::Matrix3d, Eigen::NoQRPreconditioner> svd(deformationGradient,
                                                                         Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  Eigen::Matrix3d v = svd.matrixV();
  Eigen::Vector3d sigma = svd.singularValues();
  // Flipping a column of U (or V) together with the sign of the matching singular value
  // leaves U diag(sigma) V^T unchanged; the smallest one is flipped so that an inverted
  // element is treated as compressed through its thinnest direction.
  if (u.determinant() < 0.0) {
    u.col(2) = -u.col(2);
    sigma[2] = -sigma[2];
  }
  if (v.determinant() < 0.0) {
    v.col(2) = -v.col(2);
    sigma[2] = -sigma[2];
  }
  PolarDecomposition polar;
  polar.rotation.noalias() = u * v.transpose();
  polar.stretch.noalias() = v * sigma.asDiagonal() * v.transpose();
  // S is symmetric in exact arithmetic; copying one triangle makes it so in floating
  // point too, which the torque-free forces rely on.
  polar.stretch(1, 0) = polar.stretch(0, 1);
  polar.stretch(2, 0) = polar.stretch(0, 2);
  polar.stretch(2, 1) = polar.stretch(1, 2);
  polar.rightSingularVectors = v;
  polar.singularValues = sigma;
  return polar;
}

Eigen::Matrix3d rotationDifferentialOperator(const PolarDecomposition& polar) {
  const Eigen::Vector3d& sigma = polar.singularValues;
  // Eigenvalues of tr(S) I - S: for eigenvector i the sum of the other two values.
  const Eigen::Vector3d pairSums(sigma[1] + sigma[2], sigma[0] + sigma[2], sigma[0] + sigma[1]);
  Eigen::Vector3d inverse;
  for (int i = 0; i < 3; ++i) inverse[i] = 1.0 / std::max(pairSums[i], kMinimumSingularValuePairSum);
  const Eigen::Matrix3d& v = polar.rightSingularVectors;
  Eigen::Matrix3d result = v * inverse.asDiagonal() * v.transpose();
  result(1, 0) = result(0, 1);
  result(2, 0) = result(0, 2);
  result(2, 1) = result(1, 2);
  return result;
}

Eigen::Matrix3d rotationDifferential(const PolarDecomposition& polar,
                                     const Eigen::Matrix3d& deformationGradientDifferential) {
  const Eigen::Matrix3d a = polar.rotation.transpose() * deformationGradientDifferential;
  const Eigen::Matrix3d skewPart = a - a.transpose();
  const Eigen::Vector3d axial(skewPart(2, 1), skewPart(0, 2), skewPart(1, 0));
  const Eigen::Vector3d w = rotationDifferentialOperator(polar) * axial;
  Eigen::Matrix3d cross;
  cross << 0.0, -w[2], w[1], w[2], 0.0, -w[0], -w[1], w[0], 0.0;
  return polar.rotation * cross;
}

}  // namespace asyncfem
