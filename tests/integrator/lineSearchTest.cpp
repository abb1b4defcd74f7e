// SPDX-License-Identifier: BSD-3-Clause
// Backward Euler's line search on the incremental potential and the Rayleigh damping
// option, on a hyperelastic (neo-Hookean) bar.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/problem/problem.hpp>
#include <cmath>
#include <vector>

#include "../common/testProblems.hpp"

namespace asyncfem {
namespace {

// The rubber cantilever of testProblems.hpp (1 x 0.2 x 0.2, 4 x 1 x 1 cubes, the x = 0 face
// fixed), neo-Hookean, whose material moves at v_y = speed * x: a fast swing that a step
// of h = 0.05 s (about the bar's first period) turns into a large rotation.
struct SwingingBar : test::TestBody {
  using TestBody::TestBody;
  Eigen::VectorXd initialVelocity;
};

SwingingBar makeSwingingBar(double speed, double beta = 0.0, bool enforceSPD = true) {
  HyperelasticOptions options;
  options.inversionThreshold = 0.2;
  options.enforceSPD = enforceSPD;  // Cholesky needs a positive definite system for large steps
  ProblemSettings settings = test::testSettings(ForceModelType::neoHookean, 0.0, beta);
  settings.hyperelastic = options;
  SwingingBar bar(test::rubberBarProblem(settings));
  bar.initialVelocity = Eigen::VectorXd::Zero(bar.mesh.numDofs());
  for (int v = 0; v < bar.mesh.numVertices(); ++v) {
    if (bar.mesh.restPosition(v).x() > 0.0) bar.initialVelocity[(3 * v) + 1] = speed * bar.mesh.restPosition(v).x();
  }
  return bar;
}

// The incremental potential of a step from (u0 = 0, v0) with velocity change dv (all
// full vectors, fixed DOFs zero), computed here from its definition (backwardEuler.hpp):
// Phi = 1/2 dv^T M dv + E(h (v0 + dv)), no damping or external force.
double potential(SwingingBar& bar, const Eigen::VectorXd& dv, double h) {
  return (0.5 * dv.dot(bar.system.mass * dv)) + bar.system.forceModel->elasticEnergy(h * (bar.initialVelocity + dv));
}

struct StepResult {
  Eigen::VectorXd velocity;
  double relativeResidual = 0.0;
  int halvings = 0;
  bool threw = false;
};

StepResult oneStep(double speed, double h, const IntegratorOptions& options, double beta = 0.0,
                   bool enforceSPD = true) {
  SwingingBar bar = makeSwingingBar(speed, beta, enforceSPD);
  BackwardEuler integrator(bar.system, h, options);
  integrator.setState(Eigen::VectorXd::Zero(bar.mesh.numDofs()), bar.initialVelocity);
  StepResult result;
  try {
    integrator.step();
  } catch (const NumericalError&) {
    result.threw = true;
    return result;
  }
  result.velocity = integrator.velocity();
  result.relativeResidual = integrator.lastRelativeResidual();
  result.halvings = integrator.lastLineSearchHalvings();
  return result;
}

TEST(BackwardEulerLineSearch, LargeStepConvergesWherePlainNewtonRaisesThePotential) {
  const double speed = 20.0;  // tip speed 20 m/s: the tip would move 1 m (the bar's length) in one step
  const double h = 0.05;
  SwingingBar bar = makeSwingingBar(speed);
  const double start = potential(bar, Eigen::VectorXd::Zero(bar.mesh.numDofs()), h);

  // Newton with the line search reaches the tolerance (the positive semi-definite
  // tangent makes its convergence linear, hence the iteration budget) and lowers Phi.
  IntegratorOptions newton;
  newton.maxIterations = 100;
  newton.tolerance = 1e-8;
  const StepResult searched = oneStep(speed, h, newton);
  ASSERT_FALSE(searched.threw);
  EXPECT_LE(searched.relativeResidual, newton.tolerance);
  EXPECT_GT(searched.halvings, 0);
  EXPECT_LT(potential(bar, searched.velocity - bar.initialVelocity, h), start);

  // Plain Newton from the same state, same budget: it ends far from a solution, at a
  // higher potential than it started from (or fails outright).
  newton.lineSearch = false;
  const StepResult plain = oneStep(speed, h, newton);
  if (!plain.threw) {
    EXPECT_GT(plain.relativeResidual, 1.0);
    EXPECT_GT(potential(bar, plain.velocity - bar.initialVelocity, h), start);
  }
}

TEST(BackwardEulerLineSearch, SmallStepsTakeFullNewtonUpdates) {
  IntegratorOptions newton;
  newton.maxIterations = 10;
  newton.tolerance = 1e-10;
  const StepResult result = oneStep(0.5, 1e-3, newton);
  ASSERT_FALSE(result.threw);
  EXPECT_EQ(result.halvings, 0);
  EXPECT_LE(result.relativeResidual, newton.tolerance);
  // Same answer as without line search, to the Newton tolerance: the search changed nothing.
  newton.lineSearch = false;
  const StepResult plain = oneStep(0.5, 1e-3, newton);
  EXPECT_LE((result.velocity - plain.velocity).norm(), 1e-12 * plain.velocity.norm());
}

TEST(BackwardEulerNewton, ConvergesQuadraticallyWithTheExactTangent) {
  // The residual after i iterations, from runs with maxIterations = i (each run repeats
  // the same deterministic iterations). With the exact neo-Hookean tangent (enforceSPD
  // off) Newton is quadratic: r_{i+1} <= C r_i^2 with a C of order one in these relative
  // units, while a linearly converging method would give r_{i+1} / r_i^2 growing as
  // r_i falls.
  std::vector<double> residuals;
  for (int iterations = 2; iterations <= 5; ++iterations) {
    IntegratorOptions newton;
    newton.maxIterations = iterations;
    newton.tolerance = 0.0;
    const StepResult result = oneStep(5.0, 0.01, newton, 0.0, false);
    ASSERT_FALSE(result.threw);
    residuals.push_back(result.relativeResidual);
  }
  ASSERT_GT(residuals[0], 1e-6);  // the first checked iterate is far from the rounding floor
  for (std::size_t i = 0; i + 1 < residuals.size() && residuals[i] > 1e-6; ++i) {
    SCOPED_TRACE(testing::Message() << "r_" << i + 2 << " = " << residuals[i] << ", next " << residuals[i + 1]);
    // 1e-11: the floor of a relative residual assembled from terms of size |b_0| that cancel.
    EXPECT_LE(residuals[i + 1], 10.0 * residuals[i] * residuals[i] + 1e-11);
  }
}

TEST(BackwardEulerRayleigh, StiffnessAtIterateChangesTheConvergedStepOnlyThroughBetaK) {
  // With beta = 0 the option is inert; with beta > 0 both variants converge and differ.
  IntegratorOptions newton;
  newton.maxIterations = 20;
  newton.tolerance = 1e-10;
  const StepResult frozenNoDamping = oneStep(5.0, 0.01, newton, 0.0);
  newton.rayleighStiffnessAtIterate = true;
  const StepResult iterateNoDamping = oneStep(5.0, 0.01, newton, 0.0);
  EXPECT_EQ((frozenNoDamping.velocity - iterateNoDamping.velocity).cwiseAbs().maxCoeff(), 0.0);

  newton.rayleighStiffnessAtIterate = false;
  const StepResult frozen = oneStep(5.0, 0.01, newton, 0.01);
  newton.rayleighStiffnessAtIterate = true;
  const StepResult atIterate = oneStep(5.0, 0.01, newton, 0.01);
  ASSERT_FALSE(frozen.threw);
  ASSERT_FALSE(atIterate.threw);
  EXPECT_LE(frozen.relativeResidual, 1e-10);
  EXPECT_LE(atIterate.relativeResidual, 1e-10);
  // K changes over a large-deformation step, so beta K v differs by far more than the
  // 1e-10 Newton tolerance.
  EXPECT_GT((frozen.velocity - atIterate.velocity).norm(), 1e-6 * frozen.velocity.norm());
}

}  // namespace
}  // namespace asyncfem
