// SPDX-License-Identifier: BSD-3-Clause
#include "detail/batchedInvariantKernel.hpp"

#include <array>
#include <cmath>

namespace asyncfem::detail {

namespace {

// One value per element of the batch. Every operation is a loop over the lanes, which
// the compiler turns into packed instructions.
struct Lanes {
  alignas(32) double v[kLanes] = {0.0, 0.0, 0.0, 0.0};

  Lanes() = default;
  explicit Lanes(double x) {
    for (double& value : v) value = x;
  }
  Lanes& operator+=(const Lanes& other) {
    for (int l = 0; l < kLanes; ++l) v[l] += other.v[l];
    return *this;
  }
  Lanes& operator-=(const Lanes& other) {
    for (int l = 0; l < kLanes; ++l) v[l] -= other.v[l];
    return *this;
  }
};

template <class Op>
inline Lanes map2(const Lanes& a, const Lanes& b, Op op) {
  Lanes r;
  for (int l = 0; l < kLanes; ++l) r.v[l] = op(a.v[l], b.v[l]);
  return r;
}
inline Lanes operator+(const Lanes& a, const Lanes& b) {
  return map2(a, b, [](double x, double y) { return x + y; });
}
inline Lanes operator-(const Lanes& a, const Lanes& b) {
  return map2(a, b, [](double x, double y) { return x - y; });
}
inline Lanes operator*(const Lanes& a, const Lanes& b) {
  return map2(a, b, [](double x, double y) { return x * y; });
}
inline Lanes operator/(const Lanes& a, const Lanes& b) {
  return map2(a, b, [](double x, double y) { return x / y; });
}
inline Lanes operator+(const Lanes& a, double b) { return a + Lanes(b); }
inline Lanes operator-(const Lanes& a, double b) { return a - Lanes(b); }
inline Lanes operator*(const Lanes& a, double b) { return a * Lanes(b); }
inline Lanes operator/(const Lanes& a, double b) { return a / Lanes(b); }
inline Lanes operator+(double a, const Lanes& b) { return Lanes(a) + b; }
inline Lanes operator-(double a, const Lanes& b) { return Lanes(a) - b; }
inline Lanes operator*(double a, const Lanes& b) { return Lanes(a) * b; }
inline Lanes operator/(double a, const Lanes& b) { return Lanes(a) / b; }
inline Lanes operator-(const Lanes& a) { return Lanes(0.0) - a; }

// The functions the energy densities of isotropicMaterials.hpp call (found by ADL).
inline Lanes log(const Lanes& a) {
  Lanes r;
  for (int l = 0; l < kLanes; ++l) r.v[l] = std::log(a.v[l]);
  return r;
}
inline Lanes sqrt(const Lanes& a) {
  Lanes r;
  for (int l = 0; l < kLanes; ++l) r.v[l] = std::sqrt(a.v[l]);
  return r;
}
inline Lanes pow(const Lanes& a, double exponent) {
  Lanes r;
  for (int l = 0; l < kLanes; ++l) r.v[l] = std::pow(a.v[l], exponent);
  return r;
}

// addCompressionResistance of isotropicMaterials.hpp for lanes (invariantDerivatives finds
// it by argument-dependent lookup): the term acts only where J < 1, so each lane decides.
void addCompressionResistance(const IsotropicMaterialConstants& constants, const std::array<Lanes, 3>& invariants,
                              InvariantDerivatives<Lanes>& out) {
  if (!(constants.compressionFactor > 0.0)) return;
  const double k = constants.compressionFactor;
  for (int l = 0; l < kLanes; ++l) {
    const double j = std::sqrt(invariants[2].v[l]);
    if (!(j < 1.0)) continue;
    out.energy.v[l] -= k * (j - 1.0) * (j - 1.0) * (j - 1.0) / 2592.0;
    out.gradient[2].v[l] -= k * (j - 1.0) * (j - 1.0) / (1728.0 * j);
    out.hessian[2][2].v[l] += k * (1.0 - j) * (1.0 + j) / (3456.0 * j * j * j);
  }
}

using Lanes33 = std::array<std::array<Lanes, 3>, 3>;

}  // namespace

void batchedInvariantTerms(HyperelasticMaterialKind kind, const IsotropicMaterialConstants& constants,
                           const ElementBatchInput& input, ElementVector* forces, ElementMatrix* tangents) {
  // F, its volume and shape gradients, lane by lane.
  Lanes33 f;
  Lanes volume;
  std::array<std::array<Lanes, 4>, 3> g;  // g[q][a] = G(q, a)
  for (int l = 0; l < kLanes; ++l) {
    const Eigen::Matrix3d& fl = input.deformationGradients[l];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) f[i][j].v[l] = fl(i, j);
    volume.v[l] = input.volumes[l];
    const Eigen::Matrix<double, 3, 4>& gl = input.shapeGradients[l];
    for (int q = 0; q < 3; ++q)
      for (int a = 0; a < 4; ++a) g[q][a].v[l] = gl(q, a);
  }
  // C = F^T F, the cofactors of F, det F and H = F^{-T} = cofactor(F) / det F.
  Lanes33 c;
  for (int k = 0; k < 3; ++k)
    for (int m = k; m < 3; ++m) {
      c[k][m] = (f[0][k] * f[0][m]) + (f[1][k] * f[1][m]) + (f[2][k] * f[2][m]);
      c[m][k] = c[k][m];
    }
  Lanes33 h;
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3;
    const int i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3;
      const int j2 = (j + 2) % 3;
      h[i][j] = (f[i1][j1] * f[i2][j2]) - (f[i1][j2] * f[i2][j1]);
    }
  }
  const Lanes determinant = (f[0][0] * h[0][0]) + (f[0][1] * h[0][1]) + (f[0][2] * h[0][2]);
  const Lanes inverseDeterminant = 1.0 / determinant;
  for (auto& row : h)
    for (Lanes& value : row) value = value * inverseDeterminant;
  Lanes i1 = c[0][0] + c[1][1] + c[2][2];
  Lanes i2;
  for (const auto& row : c)
    for (const Lanes& value : row) i2 += value * value;
  const std::array<Lanes, 3> invariants{i1, i2, determinant * determinant};
  const Lanes& i3 = invariants[2];
  InvariantDerivatives<Lanes> w;
  invariantDerivatives(kind, constants, invariants, w);

  // F C, then P = 2 W_1 F + 4 W_2 F C + 2 W_3 I3 H (K1) and the forces |V| P g_a.
  Lanes33 fc;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) fc[i][j] = (f[i][0] * c[0][j]) + (f[i][1] * c[1][j]) + (f[i][2] * c[2][j]);
  const Lanes twoW1 = 2.0 * w.gradient[0];
  const Lanes fourW2 = 4.0 * w.gradient[1];
  const Lanes twoW3I3 = 2.0 * w.gradient[2] * i3;
  if (forces != nullptr) {
    Lanes33 p;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) p[i][j] = (twoW1 * f[i][j]) + (fourW2 * fc[i][j]) + (twoW3I3 * h[i][j]);
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i) {
        const Lanes value = volume * ((p[i][0] * g[0][a]) + (p[i][1] * g[1][a]) + (p[i][2] * g[2][a]));
        for (int l = 0; l < kLanes; ++l) forces[l]((3 * a) + i) = value.v[l];
      }
  }

  // dP/dF on row-major vec(F) (K2): the invariant gradients' outer products through W_ab
  // (W_3 / I3 folded into W_33), 2 W_1 on the diagonal, then the T2 and T3 terms.
  std::array<std::array<Lanes, 9>, 3> gi;  // gi[a][3 i + j]: vec(2F), vec(4FC), vec(2 I3 H)
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      gi[0][(3 * i) + j] = 2.0 * f[i][j];
      gi[1][(3 * i) + j] = 4.0 * fc[i][j];
      gi[2][(3 * i) + j] = (2.0 * i3) * h[i][j];
    }
  std::array<std::array<Lanes, 3>, 3> second;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) second[a][b] = w.hessian[a][b];
  second[2][2] += w.gradient[2] / i3;
  // The materials' nonzero W_a and W_ab: neo-Hookean has no I2 term.
  const bool usesSecondInvariant = kind != HyperelasticMaterialKind::neoHookean;
  const int firstInvariant = usesSecondInvariant ? 0 : 2;  // neo-Hookean: W_1a = 0, W_2a = 0
  std::array<std::array<Lanes, 9>, 3> weighted;            // weighted[b][p] = sum_a gi[a][p] W_ab
  for (int b = 0; b < 3; ++b)
    for (int p = 0; p < 9; ++p) {
      Lanes sum;
      for (int a = firstInvariant; a < 3; ++a) sum += gi[a][p] * second[a][b];
      weighted[b][p] = sum;
    }
  std::array<std::array<Lanes, 9>, 9> dp;  // dp[p][q] = dP_p / dF_q
  for (int p = 0; p < 9; ++p)
    for (int q = p; q < 9; ++q) {
      Lanes sum;
      for (int b = firstInvariant; b < 3; ++b) sum += weighted[b][p] * gi[b][q];
      dp[p][q] = sum;
      dp[q][p] = sum;
    }
  for (int p = 0; p < 9; ++p) dp[p][p] += twoW1;
  const Lanes minusTwoW3I3 = -1.0 * (w.gradient[2] * i3) * 2.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int l = 0; l < 3; ++l)
        for (int k = 0; k < 3; ++k) {
          Lanes term = minusTwoW3I3 * h[i][k] * h[l][j];
          if (usesSecondInvariant) term += fourW2 * f[i][k] * f[l][j];
          dp[(3 * i) + j][(3 * l) + k] += term;
        }
  if (usesSecondInvariant) {
    Lanes33 b;  // F F^T
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) b[i][k] = (f[i][0] * f[k][0]) + (f[i][1] * f[k][1]) + (f[i][2] * f[k][2]);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) {
          dp[(3 * i) + j][(3 * i) + k] += fourW2 * c[k][j];
          dp[(3 * i) + j][(3 * k) + j] += fourW2 * b[i][k];
        }
  }

  // K(3a + c, 3b + d) = |V| sum_qs G(q, a) dp(3c + q, 3d + s) G(s, b). K is symmetric (dp
  // is, exactly, by construction): the lower triangle is computed and mirrored. First the
  // columns t(p, 3b + d) = sum_s dp(p, 3d + s) G(s, b), then K from the rows of |V| G.
  std::array<std::array<Lanes, 12>, 9> t;
  for (int p = 0; p < 9; ++p)
    for (int bv = 0; bv < 4; ++bv)
      for (int di = 0; di < 3; ++di) {
        const auto& row = dp[p];
        t[p][(3 * bv) + di] =
            (row[3 * di] * g[0][bv]) + (row[(3 * di) + 1] * g[1][bv]) + (row[(3 * di) + 2] * g[2][bv]);
      }
  for (int a = 0; a < 4; ++a) {
    const Lanes ga0 = volume * g[0][a];
    const Lanes ga1 = volume * g[1][a];
    const Lanes ga2 = volume * g[2][a];
    for (int ci = 0; ci < 3; ++ci) {
      const int row = (3 * a) + ci;
      for (int col = 0; col <= row; ++col) {
        const Lanes value = (ga0 * t[3 * ci][col]) + (ga1 * t[(3 * ci) + 1][col]) + (ga2 * t[(3 * ci) + 2][col]);
        for (int l = 0; l < kLanes; ++l) {
          tangents[l](row, col) = value.v[l];
          tangents[l](col, row) = value.v[l];
        }
      }
    }
  }
}

}  // namespace asyncfem::detail
