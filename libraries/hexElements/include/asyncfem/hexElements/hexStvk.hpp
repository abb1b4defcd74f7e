// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/hexElements/hexElementMatrices.hpp>

namespace asyncfem {

/// Saint Venant-Kirchhoff energy sum_g det J_g psi(F_g), internal force and exact tangent of
/// one trilinear hexahedron.
using HexStvkElement = HexElementEnergy;

/// StVK on the hexahedron with rest positions X and deformed positions x (3 x 8 each):
/// psi(F) = lambda/2 (tr E)^2 + mu tr(E^2), E = (F^T F - I)/2, F = x dN/dX, integrated by
/// 2 x 2 x 2 Gauss (weights det J of the rest shape). First Piola stress P = F S with
/// S = lambda tr(E) I + 2 mu E; f_a = sum_g det J_g P_g dN_a/dX. The energy of a trilinear
/// field is a polynomial of degree up to 4 per reference coordinate, so this rule is not
/// exact for it (3 x 3 x 3 is; Vega integrates its cubes in closed form); at rest the
/// tangent equals hexLinearStiffness. Throws as hexLinearStiffness for a rest shape with
/// det J <= 0 at a Gauss point. withTangent = false leaves tangent unset.
HexStvkElement hexStvk(const HexElementPositions& restPositions, const HexElementPositions& deformedPositions,
                       double youngsModulus, double poissonRatio, bool withTangent = true);
/// The same from the rest shape's Gauss-point data (hexGaussPoints, computed once per
/// element by HexStvkForceModel) and the Lame parameters (lambda, mu).
HexStvkElement hexStvk(const HexGaussPoints& rest, const HexElementPositions& deformedPositions,
                       const Eigen::Vector2d& lame, bool withTangent = true);

}  // namespace asyncfem
