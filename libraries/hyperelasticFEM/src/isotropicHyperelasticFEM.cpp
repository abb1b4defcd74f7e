// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hyperelasticFEM/isotropicHyperelasticFEM.hpp>
#include <asyncfem/stiffnessMatrix/symmetrizeElementMatrix.hpp>
#include <optional>
#include <string>
#include <vector>

#include "detail/batchedInvariantKernel.hpp"
#include "detail/invariantKernel.hpp"
#include "detail/isotropicMaterials.hpp"
#include "detail/stretchTerms.hpp"

namespace asyncfem {

namespace {

using detail::IsotropicMaterialConstants;
using detail::StretchTerms;

/// D (9x12): column 3b + c is U^T dF V for a unit change of coordinate c of vertex b,
/// i.e. the outer product of row c of U and g^_b (rotatedGradients, 3x4); entry (p, q)
/// at row 3p + q.
inline Eigen::Matrix<double, 9, 12> rotatedFrameDifferentials(const Eigen::Matrix3d& u,
                                                              const Eigen::Matrix<double, 3, 4>& rotatedGradients) {
  Eigen::Matrix<double, 9, 12> d;
  for (int b = 0; b < 4; ++b) {
    for (int c = 0; c < 3; ++c) {
      for (int p = 0; p < 3; ++p) {
        for (int q = 0; q < 3; ++q) d((3 * p) + q, (3 * b) + c) = u(c, p) * rotatedGradients(q, b);
      }
    }
  }
  return d;
}

/// The lowest element of material m, or -1 when no element has it.
int firstElementOfMaterial(const std::vector<int>& elementMaterials, int m) {
  const auto found = std::find(elementMaterials.begin(), elementMaterials.end(), m);
  return found == elementMaterials.end() ? -1 : static_cast<int>(found - elementMaterials.begin());
}

}  // namespace

SignedSvd signedSvd(const Eigen::Matrix3d& deformationGradient) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(deformationGradient, Eigen::ComputeFullU | Eigen::ComputeFullV);
  SignedSvd result{svd.matrixU(), svd.singularValues(), svd.matrixV()};
  // Make U and V rotations; each reflection removed flips the sign of the smallest
  // stretch, so det F < 0 leaves exactly that one negative.
  if (result.u.determinant() < 0.0) {
    result.u.col(2) *= -1.0;
    result.stretches[2] *= -1.0;
  }
  if (result.v.determinant() < 0.0) {
    result.v.col(2) *= -1.0;
    result.stretches[2] *= -1.0;
  }
  return result;
}

IsotropicHyperelasticFEM::IsotropicHyperelasticFEM(const TetMesh& mesh, HyperelasticMaterialKind kind,
                                                   const HyperelasticOptions& options,
                                                   std::shared_ptr<const MatrixAssembler> assembler)
    : ElementForceModel(mesh, std::move(assembler), "IsotropicHyperelasticFEM"),
      kind_(kind),
      options_(options),
      elementMaterials_(mesh.elementMaterials()) {
  detail::validateIsotropicOptions(options_, "IsotropicHyperelasticFEM");
  const std::vector<Material>& materials = mesh.materials();
  constants_.resize(materials.size());
  for (std::size_t m = 0; m < materials.size(); ++m) {
    const Material& material = materials[m];
    if (const std::optional<IsotropicMaterialConstants> constants =
            detail::isotropicMaterialConstants(kind_, material, options_)) {
      constants_[m] = *constants;
      continue;
    }
    const int firstElement = firstElementOfMaterial(elementMaterials_, static_cast<int>(m));
    if (firstElement < 0) continue;  // unused: its constants are never read
    throw ValidationError("IsotropicHyperelasticFEM: element " + std::to_string(firstElement) + " has material '" +
                          material.name +
                          "' without Mooney-Rivlin parameters: give it a 'MOONEYRIVLIN, density, mu01, mu10, v1' "
                          "line or set the Mooney-Rivlin override");
  }
}

IsotropicHyperelasticFEM::~IsotropicHyperelasticFEM() = default;

double IsotropicHyperelasticFEM::energyDensity(int element, const Eigen::Vector3d& stretches) const {
  if (element < 0 || element >= numElements()) {
    throw Error("IsotropicHyperelasticFEM::energyDensity: element " + std::to_string(element) + " is out of range");
  }
  const IsotropicMaterialConstants& constants =
      constants_[static_cast<std::size_t>(elementMaterials_[static_cast<std::size_t>(element)])];
  return detail::stretchTerms(kind_, constants, options_, {stretches[0], stretches[1], stretches[2]}, false).energy;
}

void IsotropicHyperelasticFEM::computeElement(int element, const Eigen::Matrix3d& deformationGradient, double* energy,
                                              ElementVector* force, ElementMatrix* tangent) const {
  const auto e = static_cast<std::size_t>(element);
  const IsotropicMaterialConstants& constants = constants_[static_cast<std::size_t>(elementMaterials_[e])];
  const double volume = geometry().volumes[e];
  if (options_.invariantPath && !options_.enforceSPD && detail::invariantPathApplies(deformationGradient, options_)) {
    computeElementFromInvariants(element, deformationGradient, energy, force, tangent);
    return;
  }
  const SignedSvd svd = signedSvd(deformationGradient);
  StretchTerms terms = detail::stretchTerms(kind_, constants, options_,
                                            {svd.stretches[0], svd.stretches[1], svd.stretches[2]}, tangent != nullptr);
  if (energy != nullptr) *energy = volume * terms.energy;
  if (force == nullptr && tangent == nullptr) return;
  // Shape gradients in the V frame: g^_a = V^T g_a (3x4).
  const Eigen::Matrix<double, 3, 4> rotatedGradients = svd.v.transpose() * geometry().shapeGradients[e];
  if (force != nullptr) {
    // f_a = |V| U diag(g) V^T g_a.
    const Eigen::Vector3d stress(terms.gradient[0], terms.gradient[1], terms.gradient[2]);
    const Eigen::Matrix<double, 3, 4> nodal = volume * (svd.u * (stress.asDiagonal() * rotatedGradients));
    *force = Eigen::Map<const ElementVector>(nodal.data());
  }
  if (tangent == nullptr) return;
  if (options_.enforceSPD) detail::clampToPositiveSemidefinite(terms);

  const Eigen::Matrix<double, 9, 12> d = rotatedFrameDifferentials(svd.u, rotatedGradients);
  tangent->noalias() = volume * (d.transpose() * detail::applyRotatedTangent(terms, d));
  symmetrizeElementMatrix(*tangent);
}

void IsotropicHyperelasticFEM::computeElementFromInvariants(int element, const Eigen::Matrix3d& deformationGradient,
                                                            double* energy, ElementVector* force,
                                                            ElementMatrix* tangent) const {
  const auto e = static_cast<std::size_t>(element);
  const double volume = geometry().volumes[e];
  double density = 0.0;
  Eigen::Matrix3d stress;
  Eigen::Matrix<double, 9, 9> dStressdF;
  detail::invariantStress(kind_, constants_[static_cast<std::size_t>(elementMaterials_[e])], deformationGradient,
                          density, stress, tangent != nullptr ? &dStressdF : nullptr);
  if (energy != nullptr) *energy = volume * density;
  if (force != nullptr) {
    // f_a = |V| P g_a, as on the principal-stretch path.
    const Eigen::Matrix<double, 3, 4> nodal = volume * (stress * geometry().shapeGradients[e]);
    *force = Eigen::Map<const ElementVector>(nodal.data());
  }
  if (tangent == nullptr) return;
  detail::elementTangentFromStressDerivative(dStressdF, geometry().shapeGradients[e], volume, *tangent);
  symmetrizeElementMatrix(*tangent);
}

void IsotropicHyperelasticFEM::computeBatch(int first, int count, const Eigen::Matrix3d* deformationGradients,
                                            ElementVector* forces, ElementMatrix* tangents) const {
  bool batched = options_.batchedKernel && options_.invariantPath && !options_.enforceSPD && count == detail::kLanes;
  const auto e0 = static_cast<std::size_t>(first);
  for (int i = 0; batched && i < count; ++i) {
    batched = elementMaterials_[e0 + static_cast<std::size_t>(i)] == elementMaterials_[e0] &&
              detail::invariantPathApplies(deformationGradients[i], options_);
  }
  if (!batched) {
    ElementForceModel::computeBatch(first, count, deformationGradients, forces, tangents);
    return;
  }
  const detail::ElementBatchInput input{deformationGradients, &geometry().volumes[e0], &geometry().shapeGradients[e0]};
  batchedElements_.fetch_add(count, std::memory_order_relaxed);
  detail::batchedInvariantTerms(kind_, constants_[static_cast<std::size_t>(elementMaterials_[e0])], input, forces,
                                tangents);
}

}  // namespace asyncfem
