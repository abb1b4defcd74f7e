// SPDX-License-Identifier: BSD-3-Clause
// Rest-shape quantities shared by the warping methods.
#pragma once

#include <Eigen/Core>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

namespace asyncfem::detail {

/// Rest-shape data of a mesh's elements for warping, tetrahedra and hexahedra alike (k = 4
/// or 8 vertices per element, m elements). Element e owns columns k e .. k e + k - 1 of
/// both gradient blocks, column k e + a belonging to its vertex a.
struct ElementGeometry {
  int verticesPerElement = 4;
  Eigen::MatrixXi elements;  ///< k x m connectivity
  /// grad N_a at the element's centre (1 / length): constant over a tetrahedron, at the
  /// reference centre xi = 0 of a hexahedron (exact for every affine field).
  Eigen::Matrix3Xd centreGradients;
  /// The integral of grad N_a over the element (length^2): V_e grad N_a for a tetrahedron,
  /// 2 x 2 x 2 Gauss quadrature for a hexahedron.
  Eigen::Matrix3Xd integratedGradients;
  Eigen::VectorXd volumes;  ///< |V_e|

  int numElements() const { return static_cast<int>(elements.cols()); }
};

/// The geometry of every element of mesh. Throws ValidationError naming the first element
/// whose |V| is at most 1e-14 L^3 (L its longest edge), or, for a hexahedron, whose Jacobian
/// at the centre or at a Gauss point is that small, where the gradients would not be finite.
ElementGeometry elementGeometry(const TetMesh& mesh);

/// The scalar Laplacian of element e, int grad N_a . grad N_b dV (k x k, length): V_e g^T g
/// for a tetrahedron, 2 x 2 x 2 Gauss quadrature for a hexahedron (positive definite apart
/// from the constants, with no hourglass modes).
Eigen::MatrixXd elementLaplacian(const TetMesh& mesh, const ElementGeometry& geometry, int e);

/// axial(A) = (A_21, A_02, A_10): for skew A = [w]x, the vector w.
inline Eigen::Vector3d axial(const Eigen::Matrix3d& a) { return {a(2, 1), a(0, 2), a(1, 0)}; }

/// Rotation matrix exp([w]x) by Rodrigues' formula,
///     R = I + (sin t / t) [w]x + ((1 - cos t) / t^2) [w]x^2,  t = |w| (radians),
/// with Taylor series of both coefficients below t = 0.05 (exactly I for w = 0).
Eigen::Matrix3d rotationFromVector(const Eigen::Vector3d& w);

}  // namespace asyncfem::detail
