// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <array>

namespace asyncfem {

/// Element-local DOF order of a hexahedron: local index 3 a + c for vertex a (0..7, the
/// order of hexahedron.hpp) and coordinate c (x, y, z).
using HexElementMatrix = Eigen::Matrix<double, 24, 24>;
using HexElementVector = Eigen::Matrix<double, 24, 1>;
using HexElementPositions = Eigen::Matrix<double, 3, 8>;  ///< columns = the element's vertices

/// Energy, internal force and tangent of one hexahedron under a force model.
struct HexElementEnergy {
  double energy = 0.0;       ///< units of E times volume (e.g. J)
  HexElementVector force;    ///< f_int = dE/dx (24, units of E times area, e.g. N)
  HexElementMatrix tangent;  ///< K = df_int/dx (24 x 24), or the model's approximation of it
};

/// Gradients dN_a/dX of the eight trilinear shape functions at reference point xi (3 x 8,
/// column a, units 1/length), and det J = det(dX/dxi) there (volume per reference volume;
/// the reference cube [-1, 1]^3 has volume 8).
Eigen::Matrix<double, 3, 8> hexShapeGradients(const HexElementPositions& restPositions, const Eigen::Vector3d& xi,
                                              double* jacobianDeterminant);

/// Strain-displacement matrix B (6 x 24) from the shape-function gradients: Voigt strain
/// (e_xx, e_yy, e_zz, 2 e_yz, 2 e_xz, 2 e_xy) = B u_e.
Eigen::Matrix<double, 6, 24> hexStrainDisplacement(const Eigen::Matrix<double, 3, 8>& shapeGradients);

/// Linear FEM element stiffness K_e = sum_g det J_g B_g^T C B_g over the 2 x 2 x 2 Gauss
/// points (weights 1) for isotropic material (24 x 24, units of E times length). Exact for
/// parallelepipeds (the integrand is then a polynomial of degree <= 2 in each reference
/// coordinate), the standard full integration otherwise. Symmetric, positive
/// semi-definite, six rigid-body modes in its null space; passes the patch test. Throws
/// asyncfem::ValidationError when det J <= 0 at a Gauss point.
Eigen::Matrix<double, 24, 24> hexLinearStiffness(const HexElementPositions& restPositions, double youngsModulus,
                                                 double poissonRatio);

/// Consistent mass M_ab = rho int N_a N_b dV per coordinate (24 x 24, zero between
/// different coordinates) by 2 x 2 x 2 Gauss: exact for parallelepipeds, where it is
/// rho V {8, 4, 2, 1} / 216 for vertex pairs that are equal, share an edge, a face
/// diagonal, the body diagonal. Entries sum to rho V per coordinate for any shape (det J
/// is integrated exactly). Throws as hexLinearStiffness.
Eigen::Matrix<double, 24, 24> hexConsistentMass(const HexElementPositions& restPositions, double density);
/// Row-sum lumped mass: rho int N_a dV on each diagonal entry of vertex a (rho V / 8 for
/// a parallelepiped), zero elsewhere.
Eigen::Matrix<double, 24, 24> hexLumpedMass(const HexElementPositions& restPositions, double density);

/// The rest shape of a hexahedron at its 2 x 2 x 2 Gauss points (hexahedron::gaussPoint,
/// weights 1): shape-function gradients dN/dX (3 x 8 per point) and det J (volume per
/// reference volume, the point's weight in the integrals).
struct HexGaussPoints {
  std::array<Eigen::Matrix<double, 3, 8>, 8> gradients;
  std::array<double, 8> volumes{};
};

/// Throws ValidationError when det J <= 0 at a Gauss point of restPositions (inverted or
/// degenerate rest shape), as hexLinearStiffness.
HexGaussPoints hexGaussPoints(const HexElementPositions& restPositions);

}  // namespace asyncfem
