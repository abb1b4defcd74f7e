// SPDX-License-Identifier: BSD-3-Clause
// Backward Euler with options.reuseFactor (PCG preconditioned by a kept factor) against
// the exact path on a corotational cantilever that swings through large rotations.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/problem/problem.hpp>

#include "testSystems.hpp"

namespace asyncfem::test {
namespace {

/// The rubber cantilever of bar (x = 0 fixed) with corotational forces.
DynamicSystem swingingBar(const BarBody& bar) {
  return withSettings(*bar.problem, testSettings(ForceModelType::corotational)).dynamicSystem();
}

// The bar starts bent well out of the linear range (tip displaced by 40% of its length)
// and swings freely for 100 steps.
Eigen::VectorXd largeBend(const TetMesh& mesh) {
  Eigen::VectorXd u = Eigen::VectorXd::Zero(mesh.numDofs());
  for (int vertex = 0; vertex < mesh.numVertices(); ++vertex) {
    const double x = mesh.restPosition(vertex).x();
    u[(3 * vertex) + 2] = 0.4 * x * x;
  }
  return u;
}

TEST(FactorReuseBackwardEuler, TrajectoryFollowsTheExactPathWithFewerFactorizations) {
  const BarBody bar = makeBar(MassType::consistent, 0.0, 0.0, Eigen::Vector3i(10, 2, 2));
  const Eigen::VectorXd u0 = largeBend(bar.mesh);
  IntegratorOptions reuseOptions;
  reuseOptions.reuseFactor = true;
  reuseOptions.pcgTolerance = 1e-10;
  IntegratorOptions exactOptions;
  exactOptions.reuseFactor = false;
  BackwardEuler exact(swingingBar(bar), 2e-3, exactOptions);
  BackwardEuler reused(swingingBar(bar), 2e-3, reuseOptions);
  exact.setState(u0, Eigen::VectorXd::Zero(u0.size()));
  reused.setState(u0, Eigen::VectorXd::Zero(u0.size()));
  double largestDifference = 0.0;
  for (int k = 0; k < 100; ++k) {
    exact.step();
    reused.step();
    largestDifference = std::max(largestDifference, scaledDifference(exact.displacement(), reused.displacement()));
  }
  // Each solve leaves a relative residual below 1e-10; the error of dv is at most
  // cond(A) (~1e3 for M + h^2 K at this step) times that, relative, and backward Euler
  // damps rather than amplifies perturbations: 1e-6 of the displacement scale bounds 100
  // steps of it with margin, and a wrong solve (or a stale, unconverged factor) is off by
  // the change of K over the swing, orders of magnitude more.
  EXPECT_LE(largestDifference, 1e-6);
  // The factor was kept for some steps (how many is the amortisation rule's choice: on
  // this small bar a factorization costs only a few PCG iterations).
  ASSERT_NE(reused.factorReuseStats(), nullptr);
  EXPECT_EQ(exact.factorReuseStats(), nullptr);
  const FactorReuseStats& stats = *reused.factorReuseStats();
  EXPECT_EQ(stats.solves, 100);
  EXPECT_LT(stats.refactorizations, 100);
  EXPECT_GT(stats.pcgIterations, 0);
  EXPECT_EQ(reused.stats().factorizations, stats.refactorizations);
  EXPECT_EQ(exact.stats().factorizations, 100);
}

TEST(FactorReuseBackwardEuler, NewtonIterationsConvergeWithReusedFactors) {
  const BarBody bar = makeBar(MassType::consistent, 0.0, 0.0, Eigen::Vector3i(6, 1, 1));
  const Eigen::VectorXd u0 = largeBend(bar.mesh);
  IntegratorOptions options;
  options.maxIterations = 8;
  options.tolerance = 1e-8;
  options.reuseFactor = false;
  IntegratorOptions reuseOptions = options;
  reuseOptions.reuseFactor = true;
  reuseOptions.pcgTolerance = 1e-10;
  BackwardEuler exact(swingingBar(bar), 5e-3, options);
  BackwardEuler reused(swingingBar(bar), 5e-3, reuseOptions);
  exact.setState(u0, Eigen::VectorXd::Zero(u0.size()));
  reused.setState(u0, Eigen::VectorXd::Zero(u0.size()));
  for (int k = 0; k < 10; ++k) {
    exact.step();
    reused.step();
    // The simple tangent is not the exact Jacobian, so Newton converges linearly and may
    // end at maxIterations above 1e-8; the reused path must do as well as the exact one:
    // the same residual up to what the 1e-10 inexact solves change (1e-3 relative).
    EXPECT_EQ(reused.lastIterations(), exact.lastIterations());
    EXPECT_LE(reused.lastRelativeResidual(), (1.001 * exact.lastRelativeResidual()) + 1e-10);
  }
  // Both end with residuals below 1e-7 of the step's right-hand side: their states agree
  // to about cond(J) (~1e3) times that, 1e-4 of the displacement scale bounds it.
  EXPECT_LE(scaledDifference(exact.displacement(), reused.displacement()), 1e-4);
}

// pcgSinglePrecision (the default) and the double factor as preconditioner: the summary's
// counters say which ran, and both trajectories stay within the exact path's bound of
// each other (each solve to a relative residual of 1e-10; see the first test).
TEST(FactorReuseBackwardEuler, SinglePrecisionPreconditionerFollowsTheDoubleFactor) {
  const BarBody bar = makeBar(MassType::consistent, 0.0, 0.0, Eigen::Vector3i(10, 2, 2));
  const Eigen::VectorXd u0 = largeBend(bar.mesh);
  IntegratorOptions singleOptions;
  IntegratorOptions doubleOptions;
  doubleOptions.pcgSinglePrecision = false;
  ASSERT_TRUE(singleOptions.pcgSinglePrecision);
  BackwardEuler single(swingingBar(bar), 2e-3, singleOptions);
  BackwardEuler dual(swingingBar(bar), 2e-3, doubleOptions);
  single.setState(u0, Eigen::VectorXd::Zero(u0.size()));
  dual.setState(u0, Eigen::VectorXd::Zero(u0.size()));
  double largestDifference = 0.0;
  for (int k = 0; k < 50; ++k) {
    single.step();
    dual.step();
    largestDifference = std::max(largestDifference, scaledDifference(single.displacement(), dual.displacement()));
  }
  EXPECT_LE(largestDifference, 1e-6);
  EXPECT_TRUE(single.factorReuseStats()->singlePrecisionPreconditioner);
  EXPECT_FALSE(dual.factorReuseStats()->singlePrecisionPreconditioner);
  EXPECT_GT(single.factorReuseStats()->pcgIterations, 0);
  EXPECT_NE(single.report().lines.front().find("applied in single precision"), std::string::npos)
      << single.report().lines.front();
  EXPECT_EQ(dual.report().lines.front().find("single precision"), std::string::npos);
}

TEST(FactorReuseBackwardEuler, BadOptionsAreRejected) {
  const BarBody bar = makeBar();
  IntegratorOptions options;
  options.reuseFactor = true;
  options.pcgTolerance = 0.0;
  EXPECT_THROW(BackwardEuler(swingingBar(bar), 1e-3, options), ValidationError);
  options.pcgTolerance = 1e-8;
  options.pcgRefactorIterations = 0;
  EXPECT_THROW(BackwardEuler(swingingBar(bar), 1e-3, options), ValidationError);
}

}  // namespace
}  // namespace asyncfem::test
