// SPDX-License-Identifier: BSD-3-Clause
#include "detail/stretchTerms.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <cmath>
#include <complex>
#include <limits>
#include <sstream>

namespace asyncfem::detail {

namespace {

using Array3 = std::array<double, 3>;
using Array33 = std::array<Array3, 3>;

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
inline void invariantPairTerms(const InvariantDerivatives<double>& invariants, const Array3& s, StretchTerms& terms) {
  const double f1 = invariants.gradient[0];
  const double f2 = invariants.gradient[1];
  const double f3 = invariants.gradient[2];
  for (int p = 0; p < 3; ++p) {
    const int i = kStretchPairs[p][0];
    const int j = kStretchPairs[p][1];
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
  stretchDerivatives(kind, constants, complexStretches, complexEnergy, complexGradient, &complexHessian);
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
    const int i = kStretchPairs[p][0];
    const int j = kStretchPairs[p][1];
    const double scale = std::max({1.0, std::abs(s[i]), std::abs(s[j])});
    const double gap = s[i] - s[j];
    const double sum = s[i] + s[j];
    terms.pairSum[p] =
        std::abs(gap) > kDividedDifferenceGap * scale ? (g[i] - g[j]) / gap : terms.hessian[i][i] - terms.hessian[i][j];
    terms.pairDifference[p] =
        std::abs(sum) > kDividedDifferenceGap * scale ? (g[i] + g[j]) / sum : terms.hessian[i][i] + terms.hessian[i][j];
  }
}

/// Compression resistance factor k = resistance E / (1 - 2 nu) of a material with small-
/// strain moduli E and nu; zero when the term is off.
double compressionFactor(const HyperelasticOptions& options, double youngsModulus, double poissonRatio) {
  if (!options.enableCompressionResistance) return 0.0;
  return options.compressionResistance * youngsModulus / (1.0 - (2.0 * poissonRatio));
}

}  // namespace

StretchTerms stretchTerms(HyperelasticMaterialKind kind, const IsotropicMaterialConstants& constants,
                          const HyperelasticOptions& options, const Array3& stretches, bool wantTangent) {
  StretchTerms terms;
  Array3 clampedStretches;
  std::array<bool, 3> clamped;
  const bool anyClamped = clampStretches(options, stretches, clampedStretches, clamped);
  const bool extrapolate = anyClamped && options.inversionHandling == InversionHandling::extrapolate;
  InvariantDerivatives<double> invariants;
  Array33 hessian{};
  stretchDerivatives(kind, constants, clampedStretches, terms.energy, terms.gradient,
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

void validateIsotropicOptions(const HyperelasticOptions& options, const std::string& owner) {
  const double threshold = options.inversionThreshold;
  if (std::isnan(threshold) || (options.inversionHandlingEnabled() && !(threshold > 0.0 && threshold < 1.0))) {
    std::ostringstream message;
    message << owner << ": inversion threshold " << threshold
            << " is out of range: use a principal stretch in (0, 1), or -infinity to disable inversion handling";
    throw ValidationError(message.str());
  }
  if (!std::isfinite(options.compressionResistance) || options.compressionResistance < 0.0) {
    std::ostringstream message;
    message << owner << ": compression resistance " << options.compressionResistance << " must be finite and >= 0";
    throw ValidationError(message.str());
  }
}

std::optional<IsotropicMaterialConstants> isotropicMaterialConstants(HyperelasticMaterialKind kind,
                                                                     const Material& material,
                                                                     const HyperelasticOptions& options) {
  IsotropicMaterialConstants constants;
  if (kind != HyperelasticMaterialKind::mooneyRivlin) {
    const LameParameters lame = vegaLameParameters(material.youngsModulus, material.poissonRatio);
    constants.lambda = lame.lambda;
    constants.mu = lame.mu;
    constants.compressionFactor = compressionFactor(options, material.youngsModulus, material.poissonRatio);
    return constants;
  }
  const std::optional<MooneyRivlinParameters> parameters =
      options.mooneyRivlin ? options.mooneyRivlin : material.mooneyRivlin;
  if (!parameters) return std::nullopt;
  // The compression resistance uses the small-strain moduli.
  const SmallStrainModuli moduli = mooneyRivlinSmallStrainModuli(*parameters);
  constants.mooneyRivlin = *parameters;
  constants.compressionFactor = compressionFactor(options, moduli.youngsModulus, moduli.poissonRatio);
  return constants;
}

}  // namespace asyncfem::detail
