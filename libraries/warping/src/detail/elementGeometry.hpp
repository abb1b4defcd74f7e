// SPDX-License-Identifier: BSD-3-Clause
// Rest-shape quantities shared by the warping methods.
#pragma once

#include <Eigen/Core>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

namespace asyncfem::detail {

/// Shape-function gradients (3 x 4, column a = grad N_a, 1 / length) and |volume| of
/// every element. Throws ValidationError naming the first element whose |V| is at most
/// 1e-14 L^3 (L its longest edge), where the gradients would not be finite.
void elementShapeGradients(const TetMesh& mesh, std::vector<Eigen::Matrix<double, 3, 4>>& gradients,
                           Eigen::VectorXd& volumes);

/// Displacement gradient G = sum_a u_a (grad N_a)^T of one element (3x3), from the
/// element's vertex displacements (columns) and its shape gradients.
inline Eigen::Matrix3d displacementGradient(const Eigen::Matrix<double, 3, 4>& vertexDisplacements,
                                            const Eigen::Matrix<double, 3, 4>& shapeGradients) {
  return vertexDisplacements * shapeGradients.transpose();
}

/// axial(A) = (A_21, A_02, A_10): for skew A = [w]x, the vector w.
inline Eigen::Vector3d axial(const Eigen::Matrix3d& a) { return {a(2, 1), a(0, 2), a(1, 0)}; }

/// Rotation matrix exp([w]x) by Rodrigues' formula,
///     R = I + (sin t / t) [w]x + ((1 - cos t) / t^2) [w]x^2,  t = |w| (radians),
/// with Taylor series of both coefficients below t = 0.05 (exactly I for w = 0).
Eigen::Matrix3d rotationFromVector(const Eigen::Vector3d& w);

}  // namespace asyncfem::detail
