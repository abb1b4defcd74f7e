// SPDX-License-Identifier: BSD-3-Clause
// The isotropic materials' stress and its derivative written directly in the deformation
// gradient F through the invariants of C = F^T F (I1 = tr C, I2 = tr C^2, I3 = det C), no
// singular value decomposition. Where no stretch is clamped these are the same derivatives
// of the same W(I1, I2, I3) that the principal-stretch path computes, so both agree to
// rounding; IsotropicHyperelasticFEM takes this path for such elements (docs/benchmarks.md,
// "Hyperelastic element kernels").
#pragma once

#include <Eigen/Core>
#include <asyncfem/hyperelasticFEM/hyperelasticOptions.hpp>

#include "isotropicMaterials.hpp"

namespace asyncfem::detail {

/// Whether the invariant path gives element F the principal-stretch path's result: det F > 0
/// and, with inversion handling on, every principal stretch at least the threshold c with a
/// relative margin (C - c^2 (1 + 1e-8) I positive definite by its leading minors, so no SVD
/// is needed to decide); near the threshold the principal-stretch path decides as before.
bool invariantPathApplies(const Eigen::Matrix3d& deformationGradient, const HyperelasticOptions& options);

/// Energy density W, first Piola-Kirchhoff stress P = dW/dF and, when dStressdF is not
/// null, dP/dF as a 9x9 matrix on vec(F) row-major (entry F_ij at index 3 i + j):
///
///   P     = 2 W_1 F + 4 W_2 F C + 2 W_3 I3 F^{-T}                                  (K1)
///   dP/dF = sum_ab W_ab g_a g_b^T + 2 W_1 Id + 4 W_2 T2 + W_3 (4 I3 h h^T - 2 I3 T3)  (K2)
///
/// with g_1 = vec(2F), g_2 = vec(4FC), g_3 = vec(2 I3 F^{-T}), h = vec(F^{-T}),
/// T2 dF = dF C + F dF^T F + F F^T dF and T3 dF = F^{-T} dF^T F^{-T} (the derivatives of
/// F C and F^{-T}), W_a and W_ab the invariant derivatives of isotropicMaterials.hpp.
/// Requires det F != 0.
void invariantStress(HyperelasticMaterialKind kind, const IsotropicMaterialConstants& constants,
                     const Eigen::Matrix3d& deformationGradient, double& energy, Eigen::Matrix3d& stress,
                     Eigen::Matrix<double, 9, 9>* dStressdF);

/// K_e = volume G^T (dP/dF) G per 3x3 block: entry (3a + c, 3b + d) is
/// volume sum_qs G(q, a) dPdF(3c + q, 3d + s) G(s, b), G the 3x4 shape gradients.
void elementTangentFromStressDerivative(const Eigen::Matrix<double, 9, 9>& dStressdF,
                                        const Eigen::Matrix<double, 3, 4>& shapeGradients, double volume,
                                        Eigen::Matrix<double, 12, 12>& tangent);

}  // namespace asyncfem::detail
