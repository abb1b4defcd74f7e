// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/hyperelasticFEM/hyperelasticOptions.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <memory>

namespace asyncfem {

namespace detail {
struct IsotropicMaterialConstants;
}

/// The material law of IsotropicHyperelasticFEM at one material point, for elements that
/// integrate it themselves (the hexahedra of library hexElements at their Gauss points):
/// energy density W(F), first Piola-Kirchhoff stress P = dW/dF and dP/dF of a kind and a
/// material, with the same options and the same computation as the tetrahedra take:
///   - F with det F > 0 and every stretch above the inversion threshold (options.
///     invariantPath, no enforceSPD): through the invariants of C, no SVD;
///   - otherwise through the principal stretches of signedSvd(F), with the inversion
///     handling of options (extrapolate or vegaClamp below inversionThreshold) and, with
///     enforceSPD, the stretch block and the 2x2 rotation blocks of dP/dF clamped to
///     positive semi-definite.
/// options.batchedKernel is not read (one point at a time).
class IsotropicMaterialPoint {
 public:
  /// Throws ValidationError for out-of-range options (as IsotropicHyperelasticFEM) and for
  /// Mooney-Rivlin when neither options.mooneyRivlin nor the material has parameters
  /// (naming the material).
  IsotropicMaterialPoint(HyperelasticMaterialKind kind, const Material& material,
                         const HyperelasticOptions& options = {});

  HyperelasticMaterialKind kind() const { return kind_; }
  const HyperelasticOptions& options() const { return options_; }

  /// W(F) (per rest volume, stress units), P (3x3) and dP/dF (9x9 on vec(F) row-major:
  /// entry F_ij at index 3 i + j, symmetric), each written when not null. Without inversion
  /// handling, neo-Hookean and Mooney-Rivlin see |det F| only and give non-finite values at
  /// det F = 0, as on tetrahedra.
  void evaluate(const Eigen::Matrix3d& deformationGradient, double* energy, Eigen::Matrix3d* stress,
                Eigen::Matrix<double, 9, 9>* stressDerivative) const;

 private:
  HyperelasticMaterialKind kind_;
  HyperelasticOptions options_;
  std::shared_ptr<const detail::IsotropicMaterialConstants> constants_;
};

}  // namespace asyncfem
