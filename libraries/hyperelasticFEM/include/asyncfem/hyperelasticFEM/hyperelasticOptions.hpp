// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

namespace asyncfem {

/// The hyperelastic materials of this library (strain energy densities W per rest volume,
/// C = F^T F with invariants I1 = tr C, I2 = tr(C^2) as Vega FEM writes them, J = det F):
enum class HyperelasticMaterialKind {
  /// Saint Venant-Kirchhoff: W = lambda/2 (tr E)^2 + mu tr(E^2), E = (C - I)/2.
  stvk,
  /// Compressible neo-Hookean: W = mu/2 (I1 - 3) - mu log J + lambda/2 (log J)^2.
  neoHookean,
  /// Vega's compressible Mooney-Rivlin: W = mu01 (I2bar - 3) + mu10 (I1bar - 3)
  /// + v1 (J - 1)^2 (see MooneyRivlinParameters).
  mooneyRivlin,
};

/// "stvk", "neo-hookean" or "mooney-rivlin" (case-insensitive; "neohookean" and
/// "mooneyrivlin" are accepted too). Throws ValidationError naming the value and the
/// accepted ones otherwise.
HyperelasticMaterialKind parseHyperelasticMaterialKind(std::string_view name);
/// The canonical name ("stvk", "neo-hookean", "mooney-rivlin").
std::string toString(HyperelasticMaterialKind kind);

/// What the principal-stretch models do with stretches below options.inversionThreshold.
enum class InversionHandling {
  /// The energy is continued below the threshold c by its first-order Taylor expansion
  /// in each stretch below c (Irving, Teran & Fedkiw 2004 clamp the stretches for the
  /// stress; here the energy is extended consistently): W~(s) = W(s^) + sum_i g_i(s^)
  /// (s_i - c), s^ = max(s, c) per stretch, g = dW/ds. The stress in a clamped direction
  /// stays the one at the threshold (a constant push back to uninverted shapes), forces
  /// are exactly minus the gradient of the energy and the tangent is exactly its Hessian.
  extrapolate,
  /// Vega FEM's IsotropicHyperelasticFEM: the stretches are clamped to c and energy,
  /// stress and tangent are all evaluated at the clamped stretches. Forces are then not
  /// the gradient of the energy below the threshold; use it to reproduce Vega runs.
  vegaClamp,
};

/// Which computation the stvk kind uses.
enum class StVKFormulation {
  /// Green-strain form P = F S, S = lambda tr(E) I + 2 mu E, as Vega's StVKForceModel
  /// (no SVD, fastest; no inversion threshold or compression resistance).
  greenStrain,
  /// Through principal stretches like the other kinds (Vega's invertible StVK), so the
  /// inversion threshold, compression resistance and enforceSPD apply.
  principalStretches,
};

/// Options of the hyperelastic force models. The defaults are Vega FEM's library
/// defaults, so a Vega model moves the same.
struct HyperelasticOptions {
  /// Principal stretch c (dimensionless) below which inversion handling starts; must be
  /// in (0, 1), or -infinity (also any value <= -DBL_MAX, Vega's default) to disable
  /// it. Vega suggests about 0.1 (0.5 for StVK, whose energy softens under compression).
  double inversionThreshold = -std::numeric_limits<double>::infinity();
  InversionHandling inversionHandling = InversionHandling::extrapolate;
  /// Vega's compression resistance: adds -k (J - 1)^3 / 2592 to W while J < 1, with
  /// k = compressionResistance * E / (1 - 2 nu) (for Mooney-Rivlin E and nu are the
  /// small-strain equivalents of mu01, mu10, v1). Off in Vega's library, on with 500 in
  /// its interactive simulator.
  bool enableCompressionResistance = false;
  /// The dimensionless factor of the compression resistance (see above).
  double compressionResistance = 500.0;
  /// Clamp the negative eigenvalues of each element's dP/dF (the 3x3 stretch block and
  /// the three 2x2 rotation blocks, Teran et al. 2005) to zero, so every element tangent
  /// is positive semi-definite. Off by default (Vega's EnforceSPD(false)); then the
  /// tangent is the exact derivative of the forces.
  bool enforceSPD = false;
  /// See StVKFormulation; only read by the stvk kind.
  StVKFormulation stvkFormulation = StVKFormulation::greenStrain;
  /// Mooney-Rivlin parameters for every element, overriding the mesh's; without it each
  /// element's material must carry a MooneyRivlinParameters block.
  std::optional<MooneyRivlinParameters> mooneyRivlin;
  /// Elements whose stretches are all above the inversion threshold (all elements when
  /// inversion handling is off), with det F > 0 and without enforceSPD, are computed from F
  /// through the invariants of C, without a singular value decomposition: the same
  /// derivatives of the same energy, equal to the principal-stretch path to rounding and
  /// 2-3x faster (docs/benchmarks.md, "Hyperelastic element kernels"). false: every element
  /// through principal stretches (for comparisons).
  bool invariantPath = true;
  /// The element loop of the tangent evaluates four consecutive elements at once (SIMD
  /// lanes over elements, the invariant path only) where all four take the invariant path
  /// and share a material; other batches go one element at a time. StVK in the
  /// Green-strain form (StVKFEM) batches every full batch of four (no inversion path).
  /// Equal to the one-element kernel to rounding (docs/benchmarks.md, "Hyperelastic element
  /// kernels"). false: one element at a time everywhere (for comparisons).
  bool batchedKernel = true;

  /// True when a finite threshold is set.
  bool inversionHandlingEnabled() const { return inversionThreshold > -std::numeric_limits<double>::max(); }
};

/// Lame parameters (lambda, mu) of E and nu exactly as Vega FEM's ENu material computes
/// them: lambda = nu E / ((1 + nu)(1 - 2 nu)), mu = E / (2 (1 + nu)) (stress units).
struct LameParameters {
  double lambda = 0.0;
  double mu = 0.0;
};
LameParameters vegaLameParameters(double youngsModulus, double poissonRatio);

/// The small-strain Young's modulus and Poisson ratio of Mooney-Rivlin parameters, from
/// G = 2 (mu10 + mu01) and K = 2 v1: E = 9 K G / (3 K + G), nu = (3 K - 2 G) / (2 (3 K
/// + G)) (the pseudo E, nu Vega uses for its compression resistance). Throws
/// ValidationError unless G > 0, K > 0 and all are finite.
struct SmallStrainModuli {
  double youngsModulus = 0.0;
  double poissonRatio = 0.0;
};
SmallStrainModuli mooneyRivlinSmallStrainModuli(const MooneyRivlinParameters& parameters);

}  // namespace asyncfem
