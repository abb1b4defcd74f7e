// SPDX-License-Identifier: BSD-3-Clause
// The coupling coefficients against the equations they implement, (A5)-(A6) and
// (A9)-(A11) of docs/asynchronous-integrator.md, entry by entry, and against the sums
// those equations imply. The coefficients are a few products of hS, hL and small
// integers, so they agree with the formulas written out here to a few ulps: relative 1e-14.
#include <gtest/gtest.h>

#include <asyncfem/asyncIntegrator/detail/coupling.hpp>
#include <cmath>

namespace asyncfem {
namespace {

using detail::CouplingCoefficients;
using detail::couplingCoefficients;

constexpr double kTolerance = 1e-14;

void expectNear(double actual, double expected, const char* what, int m, int r) {
  EXPECT_LE(std::abs(actual - expected), kTolerance * std::max(1.0, std::abs(expected)))
      << what << " for m = " << m << ", r = " << r << ": " << actual << " against " << expected;
}

const int kRatios[] = {1, 2, 3, 8, 37, 256};
constexpr double kLargeStep = 1.0 / 120.0;

// (A9)-(A11): B_r = δ_{r1} M + hS D + r hS² K, E_i = δ_{im} M + hS D + (m - i + 1) hS² K,
// interface weight (1 - θ) hL² with θ = (m + 1) / (2m).
TEST(Coupling, StableCoefficientsAreEquationsA9ToA11) {
  for (const int m : kRatios) {
    const double hL = kLargeStep, hS = hL / m;
    const CouplingCoefficients c = couplingCoefficients(AsyncCoupling::stable, m, hL);
    ASSERT_EQ(c.bM.size(), m);
    for (int r = 1; r <= m; ++r) {
      const Eigen::Index k = r - 1;
      expectNear(c.bM[k], r == 1 ? 1.0 : 0.0, "bM", m, r);
      expectNear(c.bD[k], hS, "bD", m, r);
      expectNear(c.bK[k], r * hS * hS, "bK", m, r);
      expectNear(c.eM[k], r == m ? 1.0 : 0.0, "eM", m, r);
      expectNear(c.eD[k], hS, "eD", m, r);
      expectNear(c.eK[k], (m - r + 1) * hS * hS, "eK", m, r);
    }
    const double theta = (m + 1.0) / (2.0 * m);
    expectNear(c.interfaceWeight, (1.0 - theta) * hL * hL, "interfaceWeight", m, 0);
  }
}

// (A5)-(A6): B_r = (M + r hS D + r² hS² K) / m, E_i = hL hS K (i < m),
// E_m = M + hL D + hL hS K; nothing is taken out of A^L.
TEST(Coupling, PaperCoefficientsAreEquationsA5AndA6) {
  for (const int m : kRatios) {
    const double hL = kLargeStep, hS = hL / m;
    const CouplingCoefficients c = couplingCoefficients(AsyncCoupling::paper, m, hL);
    for (int r = 1; r <= m; ++r) {
      const Eigen::Index k = r - 1;
      expectNear(c.bM[k], 1.0 / m, "bM", m, r);
      expectNear(c.bD[k], r * hS / m, "bD", m, r);
      expectNear(c.bK[k], double(r) * r * hS * hS / m, "bK", m, r);
      expectNear(c.eM[k], r == m ? 1.0 : 0.0, "eM", m, r);
      expectNear(c.eD[k], r == m ? hL : 0.0, "eD", m, r);
      expectNear(c.eK[k], hL * hS, "eK", m, r);
    }
    EXPECT_EQ(c.interfaceWeight, 0.0);
  }
}

// L's row sees the interface mass once, the damping over the whole step (hL) and the
// stiffness with total weight hL² (for the stable coupling θ hL² on the substeps plus the
// (1 - θ) hL² of Eq. A11): the same totals as single-rate backward Euler at hL, Eq. (A1).
TEST(Coupling, LargeRowTotalsEqualBackwardEulerAtTheLargeStep) {
  for (const AsyncCoupling coupling : {AsyncCoupling::stable, AsyncCoupling::paper})
    for (const int m : kRatios) {
      const double hL = kLargeStep;
      const CouplingCoefficients c = couplingCoefficients(coupling, m, hL);
      expectNear(c.eM.sum(), 1.0, "sum eM", m, 0);
      expectNear(c.eD.sum(), hL, "sum eD", m, 0);
      expectNear(c.eK.sum() + c.interfaceWeight, hL * hL, "sum eK + interface weight", m, 0);
    }
}

// m = 1: both couplings are backward Euler's blocks at hL, B = E = M + h D + h² K (A1).
TEST(Coupling, RatioOneIsBackwardEulerForBothCouplings) {
  const double h = kLargeStep;
  for (const AsyncCoupling coupling : {AsyncCoupling::stable, AsyncCoupling::paper}) {
    const CouplingCoefficients c = couplingCoefficients(coupling, 1, h);
    for (const Eigen::VectorXd* v : {&c.bM, &c.eM}) expectNear((*v)[0], 1.0, "M weight", 1, 1);
    for (const Eigen::VectorXd* v : {&c.bD, &c.eD}) expectNear((*v)[0], h, "D weight", 1, 1);
    for (const Eigen::VectorXd* v : {&c.bK, &c.eK}) expectNear((*v)[0], h * h, "K weight", 1, 1);
    EXPECT_EQ(c.interfaceWeight, 0.0);
  }
}

}  // namespace
}  // namespace asyncfem
