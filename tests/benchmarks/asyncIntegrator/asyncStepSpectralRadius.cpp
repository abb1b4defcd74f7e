// SPDX-License-Identifier: BSD-3-Clause
// asyncStepSpectralRadius: stability of the asynchronous step itself, without meshes or
// solvers. A 1D chain of linear two-node elements (consistent mass) fixed at one end: nL
// soft, heavy elements (stiffness 1, density 1) form L, the last nS elements are stiffer
// and lighter (--stiffness, --density) and their free nodes form S. One undamped step of
// the design note's coupled system (shared/design/async-backward-euler.md, the block
// lower-Hessenberg system solved densely here) is a linear map of the state (u, v); the
// step is stable for every initial state only if that map's spectral radius is at most 1.
//
//   asyncStepSpectralRadius [--stiffness K] [--density RHO] [--dt HL] [--large N] [--small N]
//                           [--ratios M...]
//
// docs/asynchronous-integrator.md ("Stability") reports what it prints.
#include <CLI/CLI.hpp>
#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <vector>

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

MatrixXd block(const MatrixXd& a, const std::vector<int>& rows, const std::vector<int>& cols) {
  MatrixXd out(rows.size(), cols.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    for (std::size_t j = 0; j < cols.size(); ++j) out(i, j) = a(rows[i], cols[j]);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Spectral radius of one asynchronous backward Euler step on a 1D chain"};
  double stiffness = 50.0, density = 0.2, hL = 0.5;
  int large = 8, small = 2;
  std::vector<int> ratios{1, 2, 4, 8, 16, 32, 64, 128, 200};
  app.add_option("--stiffness", stiffness, "Stiffness of the S elements (L's is 1)")->check(CLI::PositiveNumber);
  app.add_option("--density", density, "Density of the S elements (L's is 1)")->check(CLI::PositiveNumber);
  app.add_option("--dt", hL, "Large timestep hL")->check(CLI::PositiveNumber);
  app.add_option("--large", large, "Elements (free nodes) in L")->check(CLI::Range(1, 200));
  app.add_option("--small", small, "Elements (free nodes) in S")->check(CLI::Range(1, 200));
  app.add_option("--ratios", ratios, "Ratios m")->check(CLI::Range(1, 2000));
  CLI11_PARSE(app, argc, argv);

  const int n = large + small;
  MatrixXd M = MatrixXd::Zero(n + 1, n + 1), K = MatrixXd::Zero(n + 1, n + 1);
  for (int e = 0; e < n; ++e) {  // element e joins nodes e and e + 1; node 0 is fixed
    const bool fast = e >= large;
    const double k = fast ? stiffness : 1.0, rho = fast ? density : 1.0;
    K(e, e) += k, K(e + 1, e + 1) += k, K(e, e + 1) -= k, K(e + 1, e) -= k;
    M(e, e) += rho / 3, M(e + 1, e + 1) += rho / 3, M(e, e + 1) += rho / 6, M(e + 1, e) += rho / 6;
  }
  M = M.bottomRightCorner(n, n).eval();
  K = K.bottomRightCorner(n, n).eval();
  std::vector<int> L, S;
  for (int i = 0; i < n; ++i) (i < large ? L : S).push_back(i);
  const MatrixXd Mss = block(M, S, S), Kss = block(K, S, S), Msl = block(M, S, L), Ksl = block(K, S, L);
  const MatrixXd Mll = block(M, L, L), Kll = block(K, L, L), Mls = block(M, L, S), Kls = block(K, L, S);
  std::printf("| m | omega_max(S alone) hS | spectral radius of the step |\n|---|---|---|\n");
  const double omegaS = Eigen::GeneralizedSelfAdjointEigenSolver<MatrixXd>(Kss, Mss).eigenvalues().maxCoeff();
  for (const int m : ratios) {
    const double hS = hL / m;
    const int s = small, l = large, size = m * s + l;
    MatrixXd H = MatrixXd::Zero(size, size);
    for (int r = 1; r <= m; ++r) {
      const int row = (r - 1) * s;
      H.block(row, row, s, s) = Mss + hS * hS * Kss;                                     // A^S
      if (r >= 2) H.block(row, row - s, s, s) = hS * hS * Kss - Mss;                     // C
      for (int j = 1; j <= r - 2; ++j) H.block(row, (j - 1) * s, s, s) = hS * hS * Kss;  // G
      H.block(row, m * s, s, l) = (Msl + double(r) * r * hS * hS * Ksl) / m;             // B_r
    }
    const MatrixXd E = hL * hL * Kls / m;
    for (int j = 1; j <= m; ++j) H.block(m * s, (j - 1) * s, l, s) = j == m ? MatrixXd(Mls + E) : E;
    H.block(m * s, m * s, l, l) = Mll + hL * hL * Kll;  // A^L
    const Eigen::PartialPivLU<MatrixXd> lu(H);
    MatrixXd step(2 * n, 2 * n);
    for (int c = 0; c < 2 * n; ++c) {
      VectorXd u = VectorXd::Zero(n), v = VectorXd::Zero(n);
      (c < n ? u[c] : v[c - n]) = 1.0;
      const VectorXd Ku = K * u, Kv = K * v;
      VectorXd rhs(size);
      for (int r = 1; r <= m; ++r) {
        for (int i = 0; i < s; ++i) rhs[(r - 1) * s + i] = hS * (-Ku[S[i]] - r * hS * Kv[S[i]]);
      }
      for (int i = 0; i < l; ++i) rhs[m * s + i] = hL * (-Ku[L[i]] - hL * Kv[L[i]]);
      const VectorXd x = lu.solve(rhs);
      VectorXd un = u, vn = v;
      for (int i = 0; i < l; ++i) {
        vn[L[i]] = v[L[i]] + x[m * s + i];
        un[L[i]] = u[L[i]] + hL * vn[L[i]];
      }
      for (int i = 0; i < s; ++i) {
        double sum = 0.0;
        for (int r = 1; r <= m; ++r) sum += v[S[i]] + x[(r - 1) * s + i];
        vn[S[i]] = v[S[i]] + x[(m - 1) * s + i];
        un[S[i]] = u[S[i]] + hS * sum;
      }
      step.col(c) << un, vn;
    }
    std::printf("| %d | %.3g | %.6f |\n", m, std::sqrt(omegaS) * hS, step.eigenvalues().cwiseAbs().maxCoeff());
  }
  return 0;
}
