// SPDX-License-Identifier: BSD-3-Clause
// Strain energy densities of the isotropic materials as functions of the invariants of
// C = F^T F in Vega FEM's form (I1 = tr C, I2 = tr C^2, I3 = det C), and their chain rule
// to the principal stretches. Templates on the scalar so that the same code runs in
// complex arithmetic (complex-step derivatives, see isotropicHyperelasticFEM.cpp).
#pragma once

#include <array>
#include <asyncfem/hyperelasticFEM/hyperelasticOptions.hpp>
#include <cmath>
#include <complex>

namespace asyncfem::detail {

/// Per-material constants of the energy densities (stress units).
struct IsotropicMaterialConstants {
  double lambda = 0.0;  ///< Lame lambda (stvk, neo-Hookean)
  double mu = 0.0;      ///< Lame mu (stvk, neo-Hookean)
  MooneyRivlinParameters mooneyRivlin;
  /// k of the compression resistance term -k (J - 1)^3 / 2592 (0: off).
  double compressionFactor = 0.0;
};

inline double realPart(double x) { return x; }
inline double realPart(const std::complex<double>& x) { return x.real(); }

/// W and its first and second derivatives with respect to (I1, I2, I3).
template <class Scalar>
struct InvariantDerivatives {
  Scalar energy{};
  std::array<Scalar, 3> gradient{};
  std::array<std::array<Scalar, 3>, 3> hessian{};
};

/// Saint Venant-Kirchhoff: lambda/2 (tr E)^2 + mu tr E^2 and its (I1, I2, I3)-derivatives
/// (out must be zero on entry).
template <class Scalar>
void stvkInvariantDerivatives(const IsotropicMaterialConstants& constants, const std::array<Scalar, 3>& invariants,
                              InvariantDerivatives<Scalar>& out) {
  const Scalar i1 = invariants[0];
  const Scalar i2 = invariants[1];
  const double lambda = constants.lambda;
  const double mu = constants.mu;
  // lambda/2 (tr E)^2 + mu tr E^2 with tr E = (I1 - 3)/2, tr E^2 = (I2 - 2 I1 + 3)/4.
  out.energy = (0.125 * lambda * (i1 - 3.0) * (i1 - 3.0)) + (0.25 * mu * (i2 - (2.0 * i1) + 3.0));
  out.gradient[0] = (0.25 * lambda * (i1 - 3.0)) - (0.5 * mu);
  out.gradient[1] = Scalar(0.25 * mu);
  out.hessian[0][0] = Scalar(0.25 * lambda);
}

/// Neo-Hookean: mu/2 (I1 - 3) - mu log J + lambda/2 (log J)^2 and its
/// (I1, I2, I3)-derivatives (out must be zero on entry).
template <class Scalar>
void neoHookeanInvariantDerivatives(const IsotropicMaterialConstants& constants,
                                    const std::array<Scalar, 3>& invariants, InvariantDerivatives<Scalar>& out) {
  using std::log;
  const Scalar i1 = invariants[0];
  const Scalar i3 = invariants[2];
  const double lambda = constants.lambda;
  const double mu = constants.mu;
  const Scalar logI3 = log(i3);  // 2 log J
  out.energy = (0.5 * mu * (i1 - 3.0)) - (0.5 * mu * logI3) + (0.125 * lambda * logI3 * logI3);
  out.gradient[0] = Scalar(0.5 * mu);
  out.gradient[2] = ((-0.5 * mu) + (0.25 * lambda * logI3)) / i3;
  out.hessian[2][2] = ((0.25 * lambda) + (0.5 * mu) - (0.25 * lambda * logI3)) / (i3 * i3);
}

/// Mooney-Rivlin in Vega's form (isochoric invariants plus v1 (J - 1)^2) and its
/// (I1, I2, I3)-derivatives (out must be zero on entry).
template <class Scalar>
void mooneyRivlinInvariantDerivatives(const IsotropicMaterialConstants& constants,
                                      const std::array<Scalar, 3>& invariants, InvariantDerivatives<Scalar>& out) {
  using std::pow;
  using std::sqrt;
  const Scalar i1 = invariants[0];
  const Scalar i2 = invariants[1];
  const Scalar i3 = invariants[2];
  const double mu01 = constants.mooneyRivlin.mu01;
  const double mu10 = constants.mooneyRivlin.mu10;
  const double v1 = constants.mooneyRivlin.v1;
  const Scalar a = pow(i3, -1.0 / 3.0);           // J^(-2/3)
  const Scalar secondClassical = (i1 * i1) - i2;  // 2 x the classical second invariant
  const Scalar rootI3 = sqrt(i3);                 // |J|
  out.energy = (0.5 * mu01 * ((secondClassical * a * a) - 6.0)) + (mu10 * ((i1 * a) - 3.0)) +
               (v1 * (rootI3 - 1.0) * (rootI3 - 1.0));
  out.gradient[0] = (mu01 * i1 * a * a) + (mu10 * a);
  out.gradient[1] = -0.5 * mu01 * a * a;
  out.gradient[2] =
      (-(mu01 / 3.0) * secondClassical * a * a / i3) - ((mu10 / 3.0) * i1 * a / i3) + (v1 * (1.0 - (1.0 / rootI3)));
  out.hessian[0][0] = mu01 * a * a;
  out.hessian[0][2] = (-(2.0 / 3.0) * mu01 * i1 * a * a / i3) - ((mu10 / 3.0) * a / i3);
  out.hessian[1][2] = (mu01 / 3.0) * a * a / i3;
  out.hessian[2][2] = ((5.0 / 9.0) * mu01 * secondClassical * a * a / (i3 * i3)) +
                      ((4.0 / 9.0) * mu10 * i1 * a / (i3 * i3)) + (0.5 * v1 / (i3 * rootI3));
  out.hessian[2][0] = out.hessian[0][2];
  out.hessian[2][1] = out.hessian[1][2];
}

/// Adds the compression resistance term -k (J - 1)^3 / 2592 (for J < 1 only) and its
/// I3-derivatives to out.
template <class Scalar>
void addCompressionResistance(const IsotropicMaterialConstants& constants, const std::array<Scalar, 3>& invariants,
                              InvariantDerivatives<Scalar>& out) {
  using std::sqrt;
  if (constants.compressionFactor > 0.0) {
    const Scalar j = sqrt(invariants[2]);
    if (realPart(j) < 1.0) {
      const double k = constants.compressionFactor;
      // dJ/dI3 = 1 / (2 J).
      out.energy -= k * (j - 1.0) * (j - 1.0) * (j - 1.0) / 2592.0;
      out.gradient[2] -= k * (j - 1.0) * (j - 1.0) / (1728.0 * j);
      out.hessian[2][2] += k * (1.0 - j) * (1.0 + j) / (3456.0 * j * j * j);
    }
  }
}

/// W of the material kind and its derivatives with respect to (I1, I2, I3), compression
/// resistance included.
template <class Scalar>
void invariantDerivatives(HyperelasticMaterialKind kind, const IsotropicMaterialConstants& constants,
                          const std::array<Scalar, 3>& invariants, InvariantDerivatives<Scalar>& out) {
  out = InvariantDerivatives<Scalar>{};
  switch (kind) {
    case HyperelasticMaterialKind::stvk:
      stvkInvariantDerivatives(constants, invariants, out);
      break;
    case HyperelasticMaterialKind::neoHookean:
      neoHookeanInvariantDerivatives(constants, invariants, out);
      break;
    case HyperelasticMaterialKind::mooneyRivlin:
      mooneyRivlinInvariantDerivatives(constants, invariants, out);
      break;
  }
  addCompressionResistance(constants, invariants, out);
}

/// d[a][i] = dI_a / ds_i for I1 = sum s_i^2, I2 = sum s_i^4, I3 = prod s_i^2, given the
/// squares s_i^2.
template <class Scalar>
std::array<std::array<Scalar, 3>, 3> invariantStretchGradients(const std::array<Scalar, 3>& s,
                                                               const std::array<Scalar, 3>& squares) {
  std::array<std::array<Scalar, 3>, 3> d{};
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    const int k = (i + 2) % 3;
    d[0][i] = 2.0 * s[i];
    d[1][i] = 4.0 * s[i] * squares[i];
    d[2][i] = 2.0 * s[i] * squares[j] * squares[k];
  }
  return d;
}

/// H = d^2W/ds^2 by the chain rule: sum_ab W_ab dI_a/ds_i dI_b/ds_j plus sum_a W_a
/// d^2I_a/ds_i ds_j, with d = invariantStretchGradients(s, squares).
template <class Scalar>
void stretchHessian(const InvariantDerivatives<Scalar>& w, const std::array<std::array<Scalar, 3>, 3>& d,
                    const std::array<Scalar, 3>& s, const std::array<Scalar, 3>& squares,
                    std::array<std::array<Scalar, 3>, 3>& hessian) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      Scalar value{};
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) value += w.hessian[a][b] * d[a][i] * d[b][j];
      if (i == j) {
        const int k = (i + 1) % 3;
        const int l = (i + 2) % 3;
        value += (2.0 * w.gradient[0]) + (12.0 * squares[i] * w.gradient[1]) +
                 (2.0 * squares[k] * squares[l] * w.gradient[2]);
      } else {
        const int k = 3 - i - j;
        value += 4.0 * s[i] * s[j] * squares[k] * w.gradient[2];
      }
      hessian[i][j] = value;
    }
  }
}

/// W(s), g = dW/ds and H = d^2W/ds^2 for principal stretches s (signed: the smallest may
/// be negative for inverted elements), by the chain rule through I1 = sum s_i^2,
/// I2 = sum s_i^4, I3 = prod s_i^2. The derivatives of I3 are written as products of
/// the other stretches, so they stay finite for a zero stretch.
template <class Scalar>
void stretchDerivatives(HyperelasticMaterialKind kind, const IsotropicMaterialConstants& constants,
                        const std::array<Scalar, 3>& s, Scalar& energy, std::array<Scalar, 3>& gradient,
                        std::array<std::array<Scalar, 3>, 3>* hessian, InvariantDerivatives<Scalar>* keep = nullptr) {
  const std::array<Scalar, 3> squares{s[0] * s[0], s[1] * s[1], s[2] * s[2]};
  const std::array<Scalar, 3> invariants{
      squares[0] + squares[1] + squares[2],
      (squares[0] * squares[0]) + (squares[1] * squares[1]) + (squares[2] * squares[2]),
      squares[0] * squares[1] * squares[2]};
  InvariantDerivatives<Scalar> w;
  invariantDerivatives(kind, constants, invariants, w);
  const std::array<std::array<Scalar, 3>, 3> d = invariantStretchGradients(s, squares);
  energy = w.energy;
  for (int i = 0; i < 3; ++i)
    gradient[i] = (w.gradient[0] * d[0][i]) + (w.gradient[1] * d[1][i]) + (w.gradient[2] * d[2][i]);
  if (hessian != nullptr) stretchHessian(w, d, s, squares, *hessian);
  if (keep != nullptr) *keep = w;
}

}  // namespace asyncfem::detail
