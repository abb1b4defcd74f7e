// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>

namespace asyncfem {

/// Element-local DOF order everywhere: local index 3*a + c for vertex a (0..3) of the
/// element and coordinate c (x, y, z); global DOF 3*v + c.
using ElementMatrix = Eigen::Matrix<double, 12, 12>;
using ElementVector = Eigen::Matrix<double, 12, 1>;
using ElementPositions = Eigen::Matrix<double, 3, 4>;  ///< columns = the element's vertices

/// Lame parameters from Young's modulus E and Poisson's ratio nu:
/// lambda = E nu / ((1+nu)(1-2nu)), mu = E / (2(1+nu)).
Eigen::Vector2d lameParameters(double youngsModulus, double poissonRatio);

/// Gradients of the four linear shape functions (3 x 4, column a = grad N_a) and the
/// signed volume of a tetrahedron with vertex positions X. Throws nothing; the caller
/// checks the volume.
Eigen::Matrix<double, 3, 4> shapeFunctionGradients(const ElementPositions& restPositions, double* signedVolume);

/// Longest edge of a tetrahedron.
double longestEdge(const ElementPositions& positions);

/// The one degeneracy rule of the toolkit: throws ValidationError
/// "[caller: ]element E is degenerate (signed volume V, longest edge L)" when |V| <= 1e-14 L^3
/// (a regular tetrahedron has V = 0.118 L^3) or V is not finite.
void checkElementVolume(int element, double signedVolume, double longestEdge, const char* caller = nullptr);

/// Linear (constant-strain) element stiffness K_e = V B^T C B for isotropic material
/// (12 x 12, units of E times length). V = |signed volume|, so either vertex order gives
/// the same matrix. Exactly symmetric, positive semi-definite, six rigid-body modes in
/// its null space. A degenerate element gives non-finite entries (callers check V).
ElementMatrix linearElementStiffness(const ElementPositions& restPositions, double youngsModulus, double poissonRatio);

/// Consistent mass of a linear tetrahedron: rho V / 20 * (1 + delta_ab) per coordinate
/// (12 x 12, zero between different coordinates). volume may be signed; |volume| is used.
ElementMatrix consistentElementMass(double volume, double density);
/// Lumped (row-sum) mass: rho |V| / 4 on each diagonal entry, zero elsewhere.
ElementMatrix lumpedElementMass(double volume, double density);

}  // namespace asyncfem
