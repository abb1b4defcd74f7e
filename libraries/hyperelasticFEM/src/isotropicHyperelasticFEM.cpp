// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hyperelasticFEM/isotropicHyperelasticFEM.hpp>
#include <asyncfem/stiffnessMatrix/symmetrizeElementMatrix.hpp>
#include <cmath>
#include <complex>
#include <limits>
#include <sstream>
#include <string>

#include "detail/batchedInvariantKernel.hpp"
#include "detail/invariantKernel.hpp"
#include "detail/isotropicMaterials.hpp"

namespace asyncfem {

namespace {

using detail::IsotropicMaterialConstants;
using Array3 = std::array<double, 3>;
using Array33 = std::array<Array3, 3>;

// Pairs (i, j), i < j, of the 2x2 rotation blocks of dP/dF.
constexpr std::array<std::array<int, 2>, 3> kPairs{{{0, 1}, {0, 2}, {1, 2}}};

/// Energy density, its stretch gradient and, when asked, the data of dP/dF in the
/// rotated frame: the 3x3 stretch Hessian and, per pair, the eigenvalues a + b and a - b
/// of the 2x2 block.
struct StretchTerms {
  double energy = 0.0;
  Array3 gradient{};
  Array33 hessian{};
  Array3 pairSum{};         // (g_i - g_j) / (s_i - s_j)
  Array3 pairDifference{};  // (g_i + g_j) / (s_i + s_j)
};

/// Relative gap below which the divided differences of the extended energy's gradient
/// are replaced by their limits: the rounding error of a divided difference grows like
/// eps / gap and the error of the limit like gap, both about 1e-7 of the values here.
constexpr double kDividedDifferenceGap = 1e-7;
/// Complex-step size: the imaginary part carries the directional derivative exactly
/// (no subtractive cancellation), so any tiny step works.
constexpr double kComplexStep = 1e-30;

/// Stretches raised to the inversion threshold where below it (when inversion handling is
/// on); clamped[i] says which. Returns whether any was.
inline bool clampStretches(const HyperelasticOptions& options, const Array3& stretches, Array3& clampedStretches,
                           std::array<bool, 3>& clamped) {
  clampedStretches = stretches;
  clamped = {false, false, false};
  bool anyClamped = false;
  if (options.inversionHandlingEnabled()) {
    for (int i = 0; i < 3; ++i) {
      if (stretches[i] < options.inversionThreshold) {
        clampedStretches[i] = options.inversionThreshold;
        clamped[i] = true;
        anyClamped = true;
      }
    }
  }
  return anyClamped;
}

/// Eigenvalues a + b and a - b of the 2x2 rotation blocks of dP/dF at stretches s: Teran
/// et al.'s alpha_ij and beta_ij in Vega's invariant form, from the invariant gradient.
inline void invariantPairTerms(const detail::InvariantDerivatives<double>& invariants, const Array3& s,
                               StretchTerms& terms) {
  const double f1 = invariants.gradient[0];
  const double f2 = invariants.gradient[1];
  const double f3 = invariants.gradient[2];
  for (int p = 0; p < 3; ++p) {
    const int i = kPairs[p][0];
    const int j = kPairs[p][1];
    const int k = 3 - i - j;
    // I3 / (s_i s_j) written as s_i s_j s_k^2 so that a zero stretch stays finite.
    const double alpha = (2.0 * f1) + (4.0 * ((s[i] * s[i]) + (s[j] * s[j])) * f2);
    const double beta = (4.0 * s[i] * s[j] * f2) - (2.0 * s[i] * s[j] * s[k] * s[k] * f3);
    terms.pairSum[p] = alpha + beta;
    terms.pairDifference[p] = alpha - beta;
  }
}

/// Hessian of the first-order extension W~ below the threshold: zero between clamped
/// stretches, H(s^) between a clamped and a free one, and H(s^) + (dH/ds . d) between
/// free ones; the directional third derivative comes from one complex-step evaluation of
/// H at s^ + i t d (d = offset = s - s^).
inline void extendedHessian(HyperelasticMaterialKind kind, const IsotropicMaterialConstants& constants,
                            const Array3& clampedStretches, const Array3& offset, const std::array<bool, 3>& clamped,
                            const Array33& hessian, Array33& extended) {
  std::array<std::complex<double>, 3> complexStretches{};
  for (int i = 0; i < 3; ++i) complexStretches[i] = {clampedStretches[i], kComplexStep * offset[i]};
  std::complex<double> complexEnergy;
  std::array<std::complex<double>, 3> complexGradient{};
  std::array<std::array<std::complex<double>, 3>, 3> complexHessian{};
  detail::stretchDerivatives(kind, constants, complexStretches, complexEnergy, complexGradient, &complexHessian);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (clamped[i] && clamped[j]) {
        extended[i][j] = 0.0;
      } else if (clamped[i] || clamped[j]) {
        extended[i][j] = hessian[i][j];
      } else {
        extended[i][j] = hessian[i][j] + (complexHessian[i][j].imag() / kComplexStep);
      }
    }
  }
}

/// Eigenvalues of the 2x2 rotation blocks from divided differences of the gradient at
/// stretches s, replaced by their limits from the Hessian where the stretches are close.
inline void dividedDifferencePairTerms(const Array3& s, StretchTerms& terms) {
  const Array3& g = terms.gradient;
  for (int p = 0; p < 3; ++p) {
    const int i = kPairs[p][0];
    const int j = kPairs[p][1];
    const double scale = std::max({1.0, std::abs(s[i]), std::abs(s[j])});
    const double gap = s[i] - s[j];
    const double sum = s[i] + s[j];
    terms.pairSum[p] =
        std::abs(gap) > kDividedDifferenceGap * scale ? (g[i] - g[j]) / gap : terms.hessian[i][i] - terms.hessian[i][j];
    terms.pairDifference[p] =
        std::abs(sum) > kDividedDifferenceGap * scale ? (g[i] + g[j]) / sum : terms.hessian[i][i] + terms.hessian[i][j];
  }
}

/// StretchTerms at the principal stretches: the energy density's derivatives, below the
/// inversion threshold clamped (Vega) or extended to first order (extrapolate); the
/// tangent data only when wantTangent.
StretchTerms stretchTerms(HyperelasticMaterialKind kind, const IsotropicMaterialConstants& constants,
                          const HyperelasticOptions& options, const Array3& stretches, bool wantTangent) {
  StretchTerms terms;
  Array3 clampedStretches;
  std::array<bool, 3> clamped;
  const bool anyClamped = clampStretches(options, stretches, clampedStretches, clamped);
  const bool extrapolate = anyClamped && options.inversionHandling == InversionHandling::extrapolate;
  detail::InvariantDerivatives<double> invariants;
  Array33 hessian{};
  detail::stretchDerivatives(kind, constants, clampedStretches, terms.energy, terms.gradient,
                             (wantTangent || extrapolate) ? &hessian : nullptr, &invariants);
  if (!extrapolate) {
    // Unclamped, or Vega's clamp: everything at the (clamped) stretches.
    if (!wantTangent) return terms;
    terms.hessian = hessian;
    invariantPairTerms(invariants, clampedStretches, terms);
    return terms;
  }

  // First-order extension below the threshold: W~ = W(s^) + sum_{i clamped} g_i(s^) d_i,
  // d = s - s^ (non-zero in the clamped stretches only).
  Array3 offset{};
  for (int i = 0; i < 3; ++i) offset[i] = stretches[i] - clampedStretches[i];
  const Array3 gradientAtThreshold = terms.gradient;
  for (int i = 0; i < 3; ++i) terms.energy += gradientAtThreshold[i] * offset[i];
  for (int j = 0; j < 3; ++j) {
    if (clamped[j]) continue;
    for (int i = 0; i < 3; ++i) terms.gradient[j] += hessian[j][i] * offset[i];
  }
  if (!wantTangent) return terms;
  extendedHessian(kind, constants, clampedStretches, offset, clamped, hessian, terms.hessian);
  dividedDifferencePairTerms(stretches, terms);
  return terms;
}

/// Sets the negative eigenvalues of the stretch block and of the 2x2 blocks to zero.
void clampToPositiveSemidefinite(StretchTerms& terms) {
  Eigen::Matrix3d block;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) block(i, j) = 0.5 * (terms.hessian[i][j] + terms.hessian[j][i]);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(block);
  if (eigen.eigenvalues().minCoeff() < 0.0) {
    const Eigen::Matrix3d clampedBlock =
        eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).asDiagonal() * eigen.eigenvectors().transpose();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) terms.hessian[i][j] = clampedBlock(i, j);
  }
  for (int p = 0; p < 3; ++p) {
    terms.pairSum[p] = std::max(terms.pairSum[p], 0.0);
    terms.pairDifference[p] = std::max(terms.pairDifference[p], 0.0);
  }
}

void validateOptions(const HyperelasticOptions& options) {
  const double threshold = options.inversionThreshold;
  if (std::isnan(threshold) || (options.inversionHandlingEnabled() && !(threshold > 0.0 && threshold < 1.0))) {
    std::ostringstream message;
    message << "IsotropicHyperelasticFEM: inversion threshold " << threshold
            << " is out of range: use a principal stretch in (0, 1), or -infinity to disable inversion handling";
    throw ValidationError(message.str());
  }
  if (!std::isfinite(options.compressionResistance) || options.compressionResistance < 0.0) {
    std::ostringstream message;
    message << "IsotropicHyperelasticFEM: compression resistance " << options.compressionResistance
            << " must be finite and >= 0";
    throw ValidationError(message.str());
  }
}

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

/// A D with A = dP^/dF^ (9x9, block structure described in the class comment): the
/// stretch Hessian on the diagonal entries, a 2x2 block per rotation pair.
inline Eigen::Matrix<double, 9, 12> applyRotatedTangent(const StretchTerms& terms,
                                                        const Eigen::Matrix<double, 9, 12>& d) {
  Eigen::Matrix<double, 9, 12> ad;
  for (int i = 0; i < 3; ++i) {
    ad.row(4 * i) =
        (terms.hessian[i][0] * d.row(0)) + (terms.hessian[i][1] * d.row(4)) + (terms.hessian[i][2] * d.row(8));
  }
  for (int p = 0; p < 3; ++p) {
    const int i = kPairs[p][0];
    const int j = kPairs[p][1];
    const double a = 0.5 * (terms.pairSum[p] + terms.pairDifference[p]);
    const double b = 0.5 * (terms.pairSum[p] - terms.pairDifference[p]);
    const int ij = (3 * i) + j;
    const int ji = (3 * j) + i;
    ad.row(ij) = (a * d.row(ij)) + (b * d.row(ji));
    ad.row(ji) = (b * d.row(ij)) + (a * d.row(ji));
  }
  return ad;
}

/// Compression resistance factor k = resistance E / (1 - 2 nu) of a material with small-
/// strain moduli E and nu; zero when the term is off.
double compressionFactor(const HyperelasticOptions& options, double youngsModulus, double poissonRatio) {
  if (!options.enableCompressionResistance) return 0.0;
  return options.compressionResistance * youngsModulus / (1.0 - (2.0 * poissonRatio));
}

/// Constants of a St. Venant-Kirchhoff or neo-Hookean material: Vega's Lame parameters.
IsotropicMaterialConstants lameConstants(const Material& material, const HyperelasticOptions& options) {
  IsotropicMaterialConstants constants;
  const LameParameters lame = vegaLameParameters(material.youngsModulus, material.poissonRatio);
  constants.lambda = lame.lambda;
  constants.mu = lame.mu;
  constants.compressionFactor = compressionFactor(options, material.youngsModulus, material.poissonRatio);
  return constants;
}

/// Constants of a Mooney-Rivlin material; the compression resistance uses its small-strain
/// moduli.
IsotropicMaterialConstants mooneyRivlinConstants(const MooneyRivlinParameters& parameters,
                                                 const HyperelasticOptions& options) {
  IsotropicMaterialConstants constants;
  const SmallStrainModuli moduli = mooneyRivlinSmallStrainModuli(parameters);
  constants.mooneyRivlin = parameters;
  constants.compressionFactor = compressionFactor(options, moduli.youngsModulus, moduli.poissonRatio);
  return constants;
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
  validateOptions(options_);
  const std::vector<Material>& materials = mesh.materials();
  constants_.resize(materials.size());
  for (std::size_t m = 0; m < materials.size(); ++m) {
    const Material& material = materials[m];
    if (kind_ != HyperelasticMaterialKind::mooneyRivlin) {
      constants_[m] = lameConstants(material, options_);
      continue;
    }
    const std::optional<MooneyRivlinParameters> parameters =
        options_.mooneyRivlin ? options_.mooneyRivlin : material.mooneyRivlin;
    if (parameters) {
      constants_[m] = mooneyRivlinConstants(*parameters, options_);
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
  return stretchTerms(kind_, constants, options_, {stretches[0], stretches[1], stretches[2]}, false).energy;
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
  StretchTerms terms = stretchTerms(kind_, constants, options_, {svd.stretches[0], svd.stretches[1], svd.stretches[2]},
                                    tangent != nullptr);
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
  if (options_.enforceSPD) clampToPositiveSemidefinite(terms);

  const Eigen::Matrix<double, 9, 12> d = rotatedFrameDifferentials(svd.u, rotatedGradients);
  tangent->noalias() = volume * (d.transpose() * applyRotatedTangent(terms, d));
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
