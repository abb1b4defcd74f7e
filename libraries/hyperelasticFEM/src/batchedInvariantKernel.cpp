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
using StressDerivative = std::array<std::array<Lanes, 9>, 9>;  // dp[p][q] = dP_p / dF_q, row-major vec(F)

// One batch's kinematics and the energy's invariant derivatives.
struct BatchKinematics {
  Lanes33 f;                              // F
  Lanes33 c;                              // C = F^T F
  Lanes33 h;                              // H = F^{-T}
  Lanes33 fc;                             // F C
  Lanes volume;                           // |V|
  std::array<std::array<Lanes, 4>, 3> g;  // g[q][a] = G(q, a), the shape gradients
  Lanes i3;                               // det C
  InvariantDerivatives<Lanes> w;
};

// Loads the lanes and computes C, H = cofactor(F) / det F, the invariants and W's derivatives.
void computeKinematics(HyperelasticMaterialKind kind, const IsotropicMaterialConstants& constants,
                       const ElementBatchInput& input, BatchKinematics& k) {
  for (int l = 0; l < kLanes; ++l) {
    const Eigen::Matrix3d& fl = input.deformationGradients[l];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) k.f[i][j].v[l] = fl(i, j);
    k.volume.v[l] = input.volumes[l];
    const Eigen::Matrix<double, 3, 4>& gl = input.shapeGradients[l];
    for (int q = 0; q < 3; ++q)
      for (int a = 0; a < 4; ++a) k.g[q][a].v[l] = gl(q, a);
  }
  const Lanes33& f = k.f;
  for (int a = 0; a < 3; ++a)
    for (int b = a; b < 3; ++b) {
      k.c[a][b] = (f[0][a] * f[0][b]) + (f[1][a] * f[1][b]) + (f[2][a] * f[2][b]);
      k.c[b][a] = k.c[a][b];
    }
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3;
    const int i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3;
      const int j2 = (j + 2) % 3;
      k.h[i][j] = (f[i1][j1] * f[i2][j2]) - (f[i1][j2] * f[i2][j1]);
    }
  }
  const Lanes determinant = (f[0][0] * k.h[0][0]) + (f[0][1] * k.h[0][1]) + (f[0][2] * k.h[0][2]);
  const Lanes inverseDeterminant = 1.0 / determinant;
  for (auto& row : k.h)
    for (Lanes& value : row) value = value * inverseDeterminant;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) k.fc[i][j] = (f[i][0] * k.c[0][j]) + (f[i][1] * k.c[1][j]) + (f[i][2] * k.c[2][j]);
  Lanes i2;
  for (const auto& row : k.c)
    for (const Lanes& value : row) i2 += value * value;
  k.i3 = determinant * determinant;
  const std::array<Lanes, 3> invariants{k.c[0][0] + k.c[1][1] + k.c[2][2], i2, k.i3};
  invariantDerivatives(kind, constants, invariants, k.w);
}

// P = 2 W_1 F + 4 W_2 F C + 2 W_3 I3 H (K1) and the forces |V| P g_a, lane l into forces[l].
void writeForces(const BatchKinematics& k, ElementVector* forces) {
  const Lanes twoW1 = 2.0 * k.w.gradient[0];
  const Lanes fourW2 = 4.0 * k.w.gradient[1];
  const Lanes twoW3I3 = 2.0 * k.w.gradient[2] * k.i3;
  Lanes33 p;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) p[i][j] = (twoW1 * k.f[i][j]) + (fourW2 * k.fc[i][j]) + (twoW3I3 * k.h[i][j]);
  for (int a = 0; a < 4; ++a)
    for (int i = 0; i < 3; ++i) {
      const Lanes value = k.volume * ((p[i][0] * k.g[0][a]) + (p[i][1] * k.g[1][a]) + (p[i][2] * k.g[2][a]));
      for (int l = 0; l < kLanes; ++l) forces[l]((3 * a) + i) = value.v[l];
    }
}

// dP/dF (K2): the invariant gradients' outer products through W_ab (W_3 / I3 folded into
// W_33), 2 W_1 on the diagonal, then the T2 and T3 terms. Exactly symmetric.
void stressDerivative(HyperelasticMaterialKind kind, const BatchKinematics& k, StressDerivative& dp) {
  const Lanes33& f = k.f;
  std::array<std::array<Lanes, 9>, 3> gi;  // gi[a][3 i + j]: vec(2F), vec(4FC), vec(2 I3 H)
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      gi[0][(3 * i) + j] = 2.0 * f[i][j];
      gi[1][(3 * i) + j] = 4.0 * k.fc[i][j];
      gi[2][(3 * i) + j] = (2.0 * k.i3) * k.h[i][j];
    }
  std::array<std::array<Lanes, 3>, 3> second = k.w.hessian;
  second[2][2] += k.w.gradient[2] / k.i3;
  // The materials' nonzero W_a and W_ab: neo-Hookean has no I1 or I2 second derivative and no I2 term.
  const bool usesSecondInvariant = kind != HyperelasticMaterialKind::neoHookean;
  const int firstInvariant = usesSecondInvariant ? 0 : 2;
  std::array<std::array<Lanes, 9>, 3> weighted;  // weighted[b][p] = sum_a gi[a][p] W_ab
  for (int b = 0; b < 3; ++b)
    for (int p = 0; p < 9; ++p) {
      Lanes sum;
      for (int a = firstInvariant; a < 3; ++a) sum += gi[a][p] * second[a][b];
      weighted[b][p] = sum;
    }
  const Lanes twoW1 = 2.0 * k.w.gradient[0];
  for (int p = 0; p < 9; ++p)
    for (int q = p; q < 9; ++q) {
      Lanes sum;
      for (int b = firstInvariant; b < 3; ++b) sum += weighted[b][p] * gi[b][q];
      if (p == q) sum += twoW1;
      dp[p][q] = sum;
      dp[q][p] = sum;
    }
  const Lanes fourW2 = 4.0 * k.w.gradient[1];
  const Lanes minusTwoW3I3 = -2.0 * (k.w.gradient[2] * k.i3);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int l = 0; l < 3; ++l)
        for (int m = 0; m < 3; ++m) {
          Lanes term = minusTwoW3I3 * k.h[i][m] * k.h[l][j];
          if (usesSecondInvariant) term += fourW2 * f[i][m] * f[l][j];
          dp[(3 * i) + j][(3 * l) + m] += term;
        }
  if (!usesSecondInvariant) return;
  Lanes33 b;  // F F^T
  for (int i = 0; i < 3; ++i)
    for (int m = 0; m < 3; ++m) b[i][m] = (f[i][0] * f[m][0]) + (f[i][1] * f[m][1]) + (f[i][2] * f[m][2]);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int m = 0; m < 3; ++m) {
        dp[(3 * i) + j][(3 * i) + m] += fourW2 * k.c[m][j];
        dp[(3 * i) + j][(3 * m) + j] += fourW2 * b[i][m];
      }
}

// K(3a + c, 3b + d) = |V| sum_qs G(q, a) dp(3c + q, 3d + s) G(s, b), symmetric because dp
// is: the lower triangle is computed and mirrored. First the columns
// t(p, 3b + d) = sum_s dp(p, 3d + s) G(s, b), then K from the rows of |V| G.
void writeTangents(const BatchKinematics& k, const StressDerivative& dp, ElementMatrix* tangents) {
  std::array<std::array<Lanes, 12>, 9> t;
  for (int p = 0; p < 9; ++p)
    for (int bv = 0; bv < 4; ++bv)
      for (int di = 0; di < 3; ++di) {
        const auto& row = dp[p];
        t[p][(3 * bv) + di] =
            (row[3 * di] * k.g[0][bv]) + (row[(3 * di) + 1] * k.g[1][bv]) + (row[(3 * di) + 2] * k.g[2][bv]);
      }
  for (int a = 0; a < 4; ++a) {
    const Lanes ga0 = k.volume * k.g[0][a];
    const Lanes ga1 = k.volume * k.g[1][a];
    const Lanes ga2 = k.volume * k.g[2][a];
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

}  // namespace

void batchedInvariantTerms(HyperelasticMaterialKind kind, const IsotropicMaterialConstants& constants,
                           const ElementBatchInput& input, ElementVector* forces, ElementMatrix* tangents) {
  BatchKinematics kinematics;
  computeKinematics(kind, constants, input, kinematics);
  if (forces != nullptr) writeForces(kinematics, forces);
  StressDerivative dp;
  stressDerivative(kind, kinematics, dp);
  writeTangents(kinematics, dp, tangents);
}

}  // namespace asyncfem::detail
