// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <array>
#include <asyncfem/hexElements/hexElementMatrices.hpp>
#include <asyncfem/hyperelasticFEM/isotropicMaterialPoint.hpp>

namespace asyncfem {

/// An isotropic hyperelastic material (IsotropicMaterialPoint: StVK, neo-Hookean or
/// Mooney-Rivlin, with its inversion handling) on the trilinear hexahedron, by 2 x 2 x 2
/// Gauss integration of the deformation gradient F_g = x dN/dX at each point:
///   energy sum_g det J_g W(F_g), f_a = sum_g det J_g P(F_g) dN_a/dX and
///   K(3a + c, 3b + d) = sum_g det J_g sum_qs dN_a/dX_q dP_cq/dF_ds dN_b/dX_s
/// (tangent only when withTangent; symmetric). The tangent is the exact derivative of the
/// forces where IsotropicMaterialPoint's dP/dF is (no enforceSPD, stretches off the
/// inversion threshold itself); at rest it is the linear stiffness of the material's
/// small-strain moduli under the same rule. Values are not checked: a flat point without
/// inversion handling gives non-finite ones.
HexElementEnergy hexIsotropicHyperelastic(const HexGaussPoints& rest, const HexElementPositions& deformedPositions,
                                          const IsotropicMaterialPoint& material, bool withTangent = true);
/// The same from the rest positions (throws as hexGaussPoints).
HexElementEnergy hexIsotropicHyperelastic(const HexElementPositions& restPositions,
                                          const HexElementPositions& deformedPositions,
                                          const IsotropicMaterialPoint& material, bool withTangent = true);

}  // namespace asyncfem
