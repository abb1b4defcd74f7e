// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/hexElements/hexElementMatrices.hpp>

namespace asyncfem {

/// Energy 1/2 v^T K_e v, internal force (exact gradient) and tangent (see hexCorotational())
/// of one corotated linear hexahedron.
using HexCorotationalElement = HexElementEnergy;

/// Corotated linear FEM on a trilinear hexahedron (the warped stiffness of Mueller & Gross
/// 2004, with the rotation of the element's centre). With rest positions X and deformed
/// positions x (3 x 8 each), the shape-function gradients g_a at the centre (xi = 0, from
/// hexShapeGradients) and the linear element stiffness K_e (hexLinearStiffness):
///   - F = sum_a x_a g_a^T, the deformation gradient at the centre, and its polar rotation R
///     (polarDecomposition: det R = +1 also for inverted elements);
///   - v = R^T x - X (vertex by vertex), E = 1/2 v^T K_e v;
///   - f = dE/dx = R K_e v + W^T t, where W (3 x 24) maps dx to the axial vector of
///     R^T dR (column 3 a + c: (tr(S) I - S)^{-1} (g_a x r_c), r_c = row c of R) and
///     t = sum_b (K_e v)_b x (R^T x)_b. On a tetrahedron t vanishes (its strain is uniform,
///     so the rotated-back displacement has a symmetric gradient everywhere); on a
///     hexahedron the gradient is symmetric only at the centre and t is second order in
///     the strain. Keeping it makes the force the exact gradient of the energy, so the
///     forces are conservative, with zero net force and torque.
/// Tangent: simpleTangent = true gives R K_e R^T (block-wise; symmetric positive
/// semi-definite). Else R K_e R^T + R (Z + K_e Y) W, symmetrised, with Z the blocks
/// -[(K_e v)_b]x and Y the blocks [(R^T x)_b]x: the derivative of R K_e v (the exact tangent
/// on tetrahedra), which leaves out the derivative of W^T t, a term of the order of the
/// strain relative to the rest. withTangent = false leaves tangent unset.
HexCorotationalElement hexCorotational(const HexElementPositions& restPositions,
                                       const Eigen::Matrix<double, 3, 8>& centreGradients,
                                       const HexElementMatrix& linearStiffness,
                                       const HexElementPositions& deformedPositions, bool simpleTangent,
                                       bool withTangent = true);

}  // namespace asyncfem
