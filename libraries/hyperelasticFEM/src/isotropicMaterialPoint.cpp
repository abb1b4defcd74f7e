// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/hyperelasticFEM/isotropicHyperelasticFEM.hpp>
#include <asyncfem/hyperelasticFEM/isotropicMaterialPoint.hpp>
#include <optional>

#include "detail/invariantKernel.hpp"
#include "detail/isotropicMaterials.hpp"
#include "detail/stretchTerms.hpp"

namespace asyncfem {

namespace {

using Matrix9d = Eigen::Matrix<double, 9, 9>;

/// M (9x9) with M(3p + q, 3c + d) = U_cp V_dq: vec(U^T dF V) = M vec(dF), row-major vecs.
Matrix9d rotatedFrameMap(const Eigen::Matrix3d& u, const Eigen::Matrix3d& v) {
  Matrix9d m;
  for (int p = 0; p < 3; ++p)
    for (int q = 0; q < 3; ++q)
      for (int c = 0; c < 3; ++c)
        for (int d = 0; d < 3; ++d) m((3 * p) + q, (3 * c) + d) = u(c, p) * v(d, q);
  return m;
}

}  // namespace

IsotropicMaterialPoint::IsotropicMaterialPoint(HyperelasticMaterialKind kind, const Material& material,
                                               const HyperelasticOptions& options)
    : kind_(kind), options_(options) {
  detail::validateIsotropicOptions(options_, "IsotropicMaterialPoint");
  const std::optional<detail::IsotropicMaterialConstants> constants =
      detail::isotropicMaterialConstants(kind_, material, options_);
  if (!constants) {
    throw ValidationError("IsotropicMaterialPoint: material '" + material.name +
                          "' has no Mooney-Rivlin parameters: give it a 'MOONEYRIVLIN, density, mu01, mu10, v1' line "
                          "or set the Mooney-Rivlin override");
  }
  constants_ = std::make_shared<const detail::IsotropicMaterialConstants>(*constants);
}

void IsotropicMaterialPoint::evaluate(const Eigen::Matrix3d& f, double* energy, Eigen::Matrix3d* stress,
                                      Matrix9d* stressDerivative) const {
  if (options_.invariantPath && !options_.enforceSPD && detail::invariantPathApplies(f, options_)) {
    double density = 0.0;
    Eigen::Matrix3d firstPiola;
    detail::invariantStress(kind_, *constants_, f, density, firstPiola, stressDerivative);
    if (energy != nullptr) *energy = density;
    if (stress != nullptr) *stress = firstPiola;
    return;
  }
  const SignedSvd svd = signedSvd(f);
  detail::StretchTerms terms =
      detail::stretchTerms(kind_, *constants_, options_, {svd.stretches[0], svd.stretches[1], svd.stretches[2]},
                           stressDerivative != nullptr);
  if (energy != nullptr) *energy = terms.energy;
  if (stress != nullptr) {
    const Eigen::Vector3d principal(terms.gradient[0], terms.gradient[1], terms.gradient[2]);
    *stress = svd.u * principal.asDiagonal() * svd.v.transpose();
  }
  if (stressDerivative == nullptr) return;
  if (options_.enforceSPD) detail::clampToPositiveSemidefinite(terms);
  // dP = U dP^ V^T with vec(dP^) = A vec(U^T dF V): dP/dF = M^T A M.
  const Matrix9d m = rotatedFrameMap(svd.u, svd.v);
  const Matrix9d product = m.transpose() * detail::applyRotatedTangent(terms, m);
  *stressDerivative = 0.5 * (product + product.transpose());
}

}  // namespace asyncfem
