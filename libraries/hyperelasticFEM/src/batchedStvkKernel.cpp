// SPDX-License-Identifier: BSD-3-Clause
#include "detail/batchedStvkKernel.hpp"

namespace asyncfem::detail {

namespace {

constexpr int L = kStvkLanes;
// A 3x3 (or 3x4) matrix with one value per lane in the innermost index.
using Lane = double[L];

// out[i][j] = sum_k a[k][i] b[k][j] (transpose of a times b), 3x3 per lane.
inline void transposeTimes(const Lane (&a)[3][3], const Lane (&b)[3][3], Lane (&out)[3][3]) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      for (int l = 0; l < L; ++l) out[i][j][l] = a[0][i][l] * b[0][j][l];
      for (int k = 1; k < 3; ++k)
        for (int l = 0; l < L; ++l) out[i][j][l] += a[k][i][l] * b[k][j][l];
    }
  }
}

// out[i][c] = sum_k a[i][k] b[k][c], a 3x3 and b 3xC per lane.
template <int C>
inline void times(const Lane (&a)[3][3], const Lane (&b)[3][C], Lane (&out)[3][C]) {
  for (int i = 0; i < 3; ++i) {
    for (int c = 0; c < C; ++c) {
      for (int l = 0; l < L; ++l) out[i][c][l] = a[i][0][l] * b[0][c][l];
      for (int k = 1; k < 3; ++k)
        for (int l = 0; l < L; ++l) out[i][c][l] += a[i][k][l] * b[k][c][l];
    }
  }
}

}  // namespace

void batchedStvkTerms(const Eigen::Matrix3d* deformationGradients, const double* volumes,
                      const Eigen::Matrix<double, 3, 4>* shapeGradients, const LameParameters* lame,
                      ElementVector* forces, ElementMatrix* tangents) {
  alignas(32) Lane f[3][3], g[3][4], volume, lambda, mu;
  for (int l = 0; l < L; ++l) {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) f[i][j][l] = deformationGradients[l](i, j);
      for (int a = 0; a < 4; ++a) g[i][a][l] = shapeGradients[l](i, a);
    }
    volume[l] = volumes[l];
    lambda[l] = lame[l].lambda;
    mu[l] = lame[l].mu;
  }
  // Green strain E = (F^T F - I) / 2 and S = lambda tr(E) I + 2 mu E.
  alignas(32) Lane c[3][3], stress[3][3], trace;
  transposeTimes(f, f, c);
  for (int l = 0; l < L; ++l) trace[l] = 0.5 * ((c[0][0][l] - 1.0) + (c[1][1][l] - 1.0) + (c[2][2][l] - 1.0));
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      for (int l = 0; l < L; ++l) stress[i][j][l] = mu[l] * (c[i][j][l] - (i == j ? 1.0 : 0.0));
    }
    for (int l = 0; l < L; ++l) stress[i][i][l] += lambda[l] * trace[l];
  }
  // h_a = F g_a; S g_b; forces |V| F (S g_a) = |V| P g_a.
  alignas(32) Lane h[3][4], sg[3][4];
  times<4>(f, g, h);
  times<4>(stress, g, sg);
  if (forces != nullptr) {
    alignas(32) Lane fsg[3][4];
    times<4>(f, sg, fsg);
    for (int l = 0; l < L; ++l)
      for (int a = 0; a < 4; ++a)
        for (int i = 0; i < 3; ++i) forces[l][3 * a + i] = volume[l] * fsg[i][a][l];
  }
  // F F^T, g_a . g_b and g_a . S g_b, then the blocks (a, b), b <= a, and their mirrors.
  alignas(32) Lane b[3][3], ft[3][3], dots[4][4], geometric[4][4];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int l = 0; l < L; ++l) ft[i][j][l] = f[j][i][l];
  times<3>(f, ft, b);
  for (int a = 0; a < 4; ++a) {
    for (int bb = 0; bb <= a; ++bb) {
      for (int l = 0; l < L; ++l) {
        dots[a][bb][l] = g[0][a][l] * g[0][bb][l] + g[1][a][l] * g[1][bb][l] + g[2][a][l] * g[2][bb][l];
        geometric[a][bb][l] = g[0][a][l] * sg[0][bb][l] + g[1][a][l] * sg[1][bb][l] + g[2][a][l] * sg[2][bb][l];
      }
    }
  }
  for (int a = 0; a < 4; ++a) {
    for (int bb = 0; bb <= a; ++bb) {
      alignas(32) Lane block[3][3];
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          for (int l = 0; l < L; ++l) {
            double value = lambda[l] * h[i][a][l] * h[j][bb][l] + mu[l] * h[i][bb][l] * h[j][a][l] +
                           mu[l] * dots[a][bb][l] * b[i][j][l];
            if (i == j) value += geometric[a][bb][l];
            block[i][j][l] = volume[l] * value;
          }
        }
      }
      for (int l = 0; l < L; ++l) {
        ElementMatrix& k = tangents[l];
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) {
            k(3 * a + i, 3 * bb + j) = block[i][j][l];
            k(3 * bb + j, 3 * a + i) = block[i][j][l];
          }
        }
      }
    }
  }
}

}  // namespace asyncfem::detail
