// SPDX-License-Identifier: BSD-3-Clause
// The principal-stretch path of the isotropic materials (Irving, Teran & Fedkiw 2004;
// Teran et al. 2005): the energy density's stretch derivatives with the inversion handling
// of HyperelasticOptions, and the rotated-frame form of dP/dF. Shared by
// IsotropicHyperelasticFEM (tetrahedra) and IsotropicMaterialPoint (one material point).
#pragma once

#include <Eigen/Core>
#include <array>
#include <asyncfem/hyperelasticFEM/hyperelasticOptions.hpp>
#include <optional>
#include <string>

#include "isotropicMaterials.hpp"

namespace asyncfem::detail {

/// Pairs (i, j), i < j, of the 2x2 rotation blocks of dP/dF.
constexpr std::array<std::array<int, 2>, 3> kStretchPairs{{{0, 1}, {0, 2}, {1, 2}}};

/// Energy density, its stretch gradient and, when asked, the data of dP/dF in the
/// rotated frame: the 3x3 stretch Hessian and, per pair, the eigenvalues a + b and a - b
/// of the 2x2 block.
struct StretchTerms {
  double energy = 0.0;
  std::array<double, 3> gradient{};
  std::array<std::array<double, 3>, 3> hessian{};
  std::array<double, 3> pairSum{};         // (g_i - g_j) / (s_i - s_j)
  std::array<double, 3> pairDifference{};  // (g_i + g_j) / (s_i + s_j)
};

/// StretchTerms at the principal stretches: the energy density's derivatives, below the
/// inversion threshold clamped (Vega) or extended to first order (extrapolate); the
/// tangent data only when wantTangent.
StretchTerms stretchTerms(HyperelasticMaterialKind kind, const IsotropicMaterialConstants& constants,
                          const HyperelasticOptions& options, const std::array<double, 3>& stretches, bool wantTangent);

/// Sets the negative eigenvalues of the stretch block and of the 2x2 blocks to zero.
void clampToPositiveSemidefinite(StretchTerms& terms);

/// A D with A = dP^/dF^ (9x9 on the rotated frame's U^T dF V, entry (p, q) at row 3p + q):
/// the stretch Hessian on the diagonal entries, a 2x2 block per rotation pair.
template <int Columns>
inline Eigen::Matrix<double, 9, Columns> applyRotatedTangent(const StretchTerms& terms,
                                                             const Eigen::Matrix<double, 9, Columns>& d) {
  Eigen::Matrix<double, 9, Columns> ad;
  for (int i = 0; i < 3; ++i) {
    ad.row(4 * i) =
        (terms.hessian[i][0] * d.row(0)) + (terms.hessian[i][1] * d.row(4)) + (terms.hessian[i][2] * d.row(8));
  }
  for (int p = 0; p < 3; ++p) {
    const int i = kStretchPairs[p][0];
    const int j = kStretchPairs[p][1];
    const double a = 0.5 * (terms.pairSum[p] + terms.pairDifference[p]);
    const double b = 0.5 * (terms.pairSum[p] - terms.pairDifference[p]);
    const int ij = (3 * i) + j;
    const int ji = (3 * j) + i;
    ad.row(ij) = (a * d.row(ij)) + (b * d.row(ji));
    ad.row(ji) = (b * d.row(ij)) + (a * d.row(ji));
  }
  return ad;
}

/// Throws ValidationError, the message starting with owner, for an inversion threshold
/// neither in (0, 1) nor disabled and for a negative or non-finite compression resistance.
void validateIsotropicOptions(const HyperelasticOptions& options, const std::string& owner);

/// The constants of material under kind and options: Vega's Lame parameters (stvk,
/// neo-Hookean) or the Mooney-Rivlin parameters (options.mooneyRivlin before the
/// material's), with the compression resistance factor; nullopt for Mooney-Rivlin when
/// neither gives parameters.
std::optional<IsotropicMaterialConstants> isotropicMaterialConstants(HyperelasticMaterialKind kind,
                                                                     const Material& material,
                                                                     const HyperelasticOptions& options);

}  // namespace asyncfem::detail
