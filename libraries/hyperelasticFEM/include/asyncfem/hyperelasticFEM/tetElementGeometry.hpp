// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

namespace asyncfem {

/// The rest-shape data every per-element force model of this library needs, computed
/// once from a TetMesh: connectivity, rest positions X (3x4 per element), shape-function
/// gradients g_a (3x4, column a = grad N_a in the rest configuration, units 1/length) and
/// rest volumes |V_e|. The deformation gradient of element e at positions x is
/// F = sum_a x_a g_a^T (dimensionless).
struct TetElementGeometry {
  /// Throws ValidationError naming the lowest degenerate element (|V| <= 1e-14 L^3 with
  /// L its longest edge, or non-finite); inverted rest elements are accepted (|V| used).
  /// caller prefixes the message ("IsotropicHyperelasticFEM").
  TetElementGeometry(const TetMesh& mesh, const char* caller);

  int numElements() const { return static_cast<int>(elements.cols()); }
  /// x = X + u of element e (3x4); u is the stacked 3n displacement.
  ElementPositions currentPositions(int e, const Eigen::VectorXd& displacement) const;
  /// F of element e at displacement u.
  Eigen::Matrix3d deformationGradient(int e, const Eigen::VectorXd& displacement) const;

  int numDofs = 0;
  Eigen::Matrix4Xi elements;
  std::vector<ElementPositions> restPositions;
  std::vector<Eigen::Matrix<double, 3, 4>> shapeGradients;
  std::vector<double> volumes;
};

}  // namespace asyncfem
