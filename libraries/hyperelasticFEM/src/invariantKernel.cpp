// SPDX-License-Identifier: BSD-3-Clause
#include "detail/invariantKernel.hpp"

#include <Eigen/LU>
#include <array>
#include <cmath>

namespace asyncfem::detail {

bool invariantPathApplies(const Eigen::Matrix3d& f, const HyperelasticOptions& options) {
  if (!(f.determinant() > 0.0)) return false;
  if (!options.inversionHandlingEnabled()) return true;
  // C - c^2 I is positive definite iff its leading principal minors are positive
  // (Sylvester), i.e. iff every principal stretch exceeds c.
  const double shift = options.inversionThreshold * options.inversionThreshold * (1.0 + 1e-8);
  Eigen::Matrix3d shifted = f.transpose() * f;
  shifted.diagonal().array() -= shift;
  const double minor1 = shifted(0, 0);
  const double minor2 = (shifted(0, 0) * shifted(1, 1)) - (shifted(0, 1) * shifted(1, 0));
  return minor1 > 0.0 && minor2 > 0.0 && shifted.determinant() > 0.0;
}

namespace {

inline Eigen::Matrix<double, 9, 1> rowMajor(const Eigen::Matrix3d& m) {
  Eigen::Matrix<double, 9, 1> v;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) v((3 * i) + j) = m(i, j);
  return v;
}

// The T2 and T3 terms of (K2): entry (3i + j, 3l + k) gets 4 W_2 F_ik F_lj - 2 W_3 I3 H_ik H_lj,
// (3i + j, 3i + k) gets 4 W_2 C_kj and (3i + j, 3k + j) gets 4 W_2 B_ik (B = F F^T).
void addSecondInvariantTerms(const Eigen::Matrix3d& f, const Eigen::Matrix3d& c, const Eigen::Matrix3d& h, double w2,
                             double w3i3, Eigen::Matrix<double, 9, 9>& a) {
  const double four = 4.0 * w2;
  const double two = -2.0 * w3i3;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int l = 0; l < 3; ++l)
        for (int k = 0; k < 3; ++k) {
          a((3 * i) + j, (3 * l) + k) += (four * f(i, k) * f(l, j)) + (two * h(i, k) * h(l, j));
        }
  if (w2 == 0.0) return;
  const Eigen::Matrix3d b = f * f.transpose();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) {
        a((3 * i) + j, (3 * i) + k) += four * c(k, j);
        a((3 * i) + j, (3 * k) + j) += four * b(i, k);
      }
}

}  // namespace

void invariantStress(HyperelasticMaterialKind kind, const IsotropicMaterialConstants& constants,
                     const Eigen::Matrix3d& f, double& energy, Eigen::Matrix3d& stress,
                     Eigen::Matrix<double, 9, 9>* dStressdF) {
  const Eigen::Matrix3d c = f.transpose() * f;
  const double determinant = f.determinant();
  const std::array<double, 3> invariants{c.trace(), c.squaredNorm(), determinant * determinant};
  InvariantDerivatives<double> w;
  invariantDerivatives(kind, constants, invariants, w);
  energy = w.energy;
  const double i3 = invariants[2];
  const Eigen::Matrix3d h = f.inverse().transpose();
  // (K1)
  stress = (2.0 * w.gradient[0]) * f + (4.0 * w.gradient[1]) * (f * c) + (2.0 * w.gradient[2] * i3) * h;
  if (dStressdF == nullptr) return;
  // (K2): the invariant-gradient outer products, with 4 W_3 I3 h h^T = (W_3 / I3) g_3 g_3^T
  // folded into W_33.
  Eigen::Matrix<double, 9, 3> g;
  g.col(0) = rowMajor(2.0 * f);
  g.col(1) = rowMajor(4.0 * (f * c));
  g.col(2) = rowMajor((2.0 * i3) * h);
  Eigen::Matrix3d second;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) second(a, b) = w.hessian[a][b];
  second(2, 2) += w.gradient[2] / i3;
  Eigen::Matrix<double, 9, 9>& a = *dStressdF;
  a.noalias() = g * (second * g.transpose());
  a.diagonal().array() += 2.0 * w.gradient[0];
  addSecondInvariantTerms(f, c, h, w.gradient[1], w.gradient[2] * i3, a);
}

void elementTangentFromStressDerivative(const Eigen::Matrix<double, 9, 9>& dStressdF,
                                        const Eigen::Matrix<double, 3, 4>& shapeGradients, double volume,
                                        Eigen::Matrix<double, 12, 12>& tangent) {
  const Eigen::Matrix<double, 3, 4> scaled = volume * shapeGradients;
  for (int c = 0; c < 3; ++c) {
    for (int d = 0; d < 3; ++d) {
      const Eigen::Matrix<double, 3, 4> right = dStressdF.block<3, 3>(3 * c, 3 * d) * shapeGradients;
      const Eigen::Matrix4d block = scaled.transpose() * right;
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) tangent((3 * a) + c, (3 * b) + d) = block(a, b);
    }
  }
}

}  // namespace asyncfem::detail
