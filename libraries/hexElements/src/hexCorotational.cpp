// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Dense>
#include <asyncfem/corotationalLinearFEM/polarDecomposition.hpp>
#include <asyncfem/hexElements/hexCorotational.hpp>

namespace asyncfem {

namespace {

Eigen::Matrix3d cross(const Eigen::Vector3d& p) {
  Eigen::Matrix3d m;
  m << 0.0, -p.z(), p.y(), p.z(), 0.0, -p.x(), -p.y(), p.x(), 0.0;
  return m;
}

}  // namespace

HexCorotationalElement hexCorotational(const HexElementPositions& restPositions,
                                       const Eigen::Matrix<double, 3, 8>& centreGradients,
                                       const HexElementMatrix& linearStiffness,
                                       const HexElementPositions& deformedPositions, bool simpleTangent,
                                       bool withTangent) {
  const PolarDecomposition polar = polarDecomposition(deformedPositions * centreGradients.transpose());
  const Eigen::Matrix3d& rotation = polar.rotation;
  const HexElementPositions rotatedBack = rotation.transpose() * deformedPositions;
  HexElementVector v;
  for (int a = 0; a < 8; ++a) v.segment<3>(3 * a) = rotatedBack.col(a) - restPositions.col(a);
  const HexElementVector kv = linearStiffness * v;
  HexCorotationalElement out;
  out.energy = 0.5 * v.dot(kv);
  // W: dx -> axial vector of R^T dR.
  const Eigen::Matrix3d solve = rotationDifferentialOperator(polar);
  Eigen::Matrix<double, 3, 24> w;
  for (int a = 0; a < 8; ++a)
    for (int c = 0; c < 3; ++c) w.col((3 * a) + c) = solve * centreGradients.col(a).cross(rotation.row(c).transpose());
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();
  for (int b = 0; b < 8; ++b) torque += kv.segment<3>(3 * b).cross(rotatedBack.col(b));
  for (int a = 0; a < 8; ++a) out.force.segment<3>(3 * a) = rotation * kv.segment<3>(3 * a);
  out.force += w.transpose() * torque;
  if (!withTangent) return out;
  HexElementMatrix rotated;  // R K_e R^T, block by block
  for (int a = 0; a < 8; ++a)
    for (int b = 0; b < 8; ++b)
      rotated.block<3, 3>(3 * a, 3 * b) = rotation * linearStiffness.block<3, 3>(3 * a, 3 * b) * rotation.transpose();
  out.tangent = rotated;
  if (simpleTangent) return out;
  Eigen::Matrix<double, 24, 3> zPlusKy = linearStiffness * [&] {
    Eigen::Matrix<double, 24, 3> y;
    for (int b = 0; b < 8; ++b) y.block<3, 3>(3 * b, 0) = cross(rotatedBack.col(b));
    return y;
  }();
  for (int b = 0; b < 8; ++b) zPlusKy.block<3, 3>(3 * b, 0) -= cross(kv.segment<3>(3 * b));
  Eigen::Matrix<double, 24, 3> rotatedZPlusKy;
  for (int b = 0; b < 8; ++b) rotatedZPlusKy.block<3, 3>(3 * b, 0) = rotation * zPlusKy.block<3, 3>(3 * b, 0);
  out.tangent += rotatedZPlusKy * w;
  out.tangent = 0.5 * (out.tangent + out.tangent.transpose()).eval();
  return out;
}

}  // namespace asyncfem
