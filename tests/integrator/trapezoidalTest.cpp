// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/integrator/trapezoidal.hpp>
#include <cmath>

#include "testSystems.hpp"

namespace asyncfem::test {
namespace {

Eigen::VectorXd wiggle(int size, double amplitude, double phase) {
  Eigen::VectorXd x(size);
  for (int i = 0; i < size; ++i) x[i] = amplitude * std::sin((1.7 * i) + phase);
  return x;
}

// Average acceleration conserves v^T M v / 2 + u^T K u / 2 exactly for linear undamped
// systems; only round-off (~1e-16 per step, a few hundred steps) remains, so 1e-10
// relative is generous. Even at h far above every period (h omega_max >> 1).
TEST(Trapezoidal, ConservesEnergyOfLinearFreeVibration) {
  BarBody body = makeBar();
  const int n = body.system.numDofs();
  for (double h : {1e-4, 1e-3, 1e-1}) {
    Trapezoidal integrator(body.system, h);
    integrator.setState(wiggle(n, 1e-3, 0.0), wiggle(n, 1e-1, 0.5));
    const double initial = integrator.mechanicalEnergy();
    for (int k = 0; k < 300; ++k) {
      integrator.step();
      ASSERT_NEAR(integrator.mechanicalEnergy(), initial, 1e-10 * initial) << "h " << h << " step " << k;
    }
    EXPECT_EQ(integrator.stats().factorizations, 2);  // system matrix + mass (initial acceleration)
  }
}

TEST(Trapezoidal, TracksAccelerationWhenStateIsSet) {
  BarBody body = makeBar(MassType::consistent, 0.2, 1e-4);
  const int n = body.system.numDofs();
  const Eigen::VectorXd u0 = body.freeDofs.expand(body.freeDofs.restrict(wiggle(n, 1e-3, 0.1)));
  const Eigen::VectorXd v0 = body.freeDofs.expand(body.freeDofs.restrict(wiggle(n, 1e-2, 0.9)));

  Trapezoidal reused(body.system, 1e-3);
  for (int k = 0; k < 5; ++k) reused.step();
  reused.setState(u0, v0, 0.5);
  reused.step();

  Trapezoidal fresh(body.system, 1e-3);
  fresh.setState(u0, v0, 0.5);
  fresh.step();
  EXPECT_LE((reused.displacement() - fresh.displacement()).norm(), 1e-14 * fresh.displacement().norm());

  // The initial acceleration solves M a = -K u - D v on the free DOFs.
  Trapezoidal check(body.system, 1e-3);
  check.setState(u0, v0);
  const Eigen::MatrixXd K = denseFree(body.stiffness, body.freeDofs);
  const Eigen::MatrixXd M = denseFree(body.mass, body.freeDofs);
  const Eigen::VectorXd u = body.freeDofs.restrict(u0), v = body.freeDofs.restrict(v0);
  const Eigen::VectorXd expected = M.ldlt().solve(-K * u - (0.2 * M + 1e-4 * K) * v);
  const Eigen::VectorXd a = body.freeDofs.restrict(check.acceleration());
  EXPECT_LE((a - expected).norm(), 1e-10 * expected.norm());
}

TEST(Trapezoidal, FixedDofsStayExactlyZero) {
  BarBody body = makeBar(MassType::lumped, 0.1, 1e-4);
  body.system.externalForce = [](double, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& f) {
    f.setConstant(-2.0);
  };
  Trapezoidal integrator(body.system, 1e-3);
  for (int k = 0; k < 20; ++k) integrator.step();
  for (int dof = 0; dof < body.system.numDofs(); ++dof) {
    if (body.freeDofs.isFixed(dof)) {
      ASSERT_EQ(integrator.displacement()[dof], 0.0);
      ASSERT_EQ(integrator.velocity()[dof], 0.0);
    }
  }
  EXPECT_GT(integrator.displacement().lpNorm<Eigen::Infinity>(), 0.0);
}

}  // namespace
}  // namespace asyncfem::test
