// SPDX-License-Identifier: BSD-3-Clause
// The asynchronous step with corotational forces (the paper's Algorithm 2), and contact.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <asyncfem/contact/penaltyContact.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <memory>
#include <utility>

#include "asyncTestSystem.hpp"

namespace asyncfem {
namespace {

using test::relativeDifference;

/// The test system of asyncTestSystem.hpp with a corotational force model instead.
test::TestSystem makeCorotationalSystem(double alpha, double beta) {
  return test::makeTestSystem(test::testSettings(ForceModelType::corotational, alpha, beta));
}

// m = 1: the nonlinear asynchronous step equals a corotational single-rate (linearized)
// backward Euler step at hL, for both couplings. Tolerance 1e-9: same equations, different
// factorizations.
TEST(NonlinearAsync, RatioOneEqualsCorotationalBackwardEuler) {
  for (const AsyncCoupling coupling : {AsyncCoupling::stable, AsyncCoupling::paper})
    for (double alpha : {0.0, 0.5}) {
      test::TestSystem ts = makeCorotationalSystem(alpha, alpha * 1e-3);
      ts.u0 *= 100.0;  // a visibly nonlinear state (~0.1 displacement on a 1-long bar)
      const double hL = 2e-3;
      AsyncBackwardEuler async(ts.mesh, ts.system, hL, {{"tip", test::verticesBeyond(ts.mesh, 0.75), 1}},
                               test::withCoupling(coupling));
      IntegratorOptions exact;  // the same equations solved exactly, as the async step does
      exact.reuseFactor = false;
      BackwardEuler single(ts.system, hL, exact);
      async.setState(ts.u0, ts.v0);
      single.setState(ts.u0, ts.v0);
      for (int k = 0; k < 4; ++k) {
        async.step();
        single.step();
      }
      EXPECT_LT(relativeDifference(async.displacement(), single.displacement()), 1e-9);
      EXPECT_LT(relativeDifference(async.velocity(), single.velocity()), 1e-9);
      // Refactored every large step: one A^S and one A^L per step.
      EXPECT_EQ(async.stats().factorizations, 2 * 4);
    }
}

/// Two async integrators with different options on the corotational test system (damped,
/// visibly nonlinear start, the tip at m = 6, hL = 2e-3), stepped side by side.
std::pair<std::unique_ptr<AsyncBackwardEuler>, std::unique_ptr<AsyncBackwardEuler>> runSideBySide(
    const AsyncOptions& first, const AsyncOptions& second, int steps) {
  test::TestSystem ts = makeCorotationalSystem(0.2, 1e-3);
  ts.u0 *= 100.0;
  const std::vector<AsyncRegion> regions{{"tip", test::verticesBeyond(ts.mesh, 0.75), 6}};
  auto a = std::make_unique<AsyncBackwardEuler>(ts.mesh, ts.system, 2e-3, regions, first);
  auto b = std::make_unique<AsyncBackwardEuler>(ts.mesh, ts.system, 2e-3, regions, second);
  a->setState(ts.u0, ts.v0);
  b->setState(ts.u0, ts.v0);
  for (int k = 0; k < steps; ++k) {
    a->step();
    b->step();
  }
  return {std::move(a), std::move(b)};
}

// The nonlinear step equals the exact-structure naive solve, with m > 1 and damping.
TEST(NonlinearAsync, StructuredEqualsNaive) {
  AsyncOptions naiveOptions;
  naiveOptions.method = AsyncSolveMethod::naive;
  const auto [structured, naive] = runSideBySide({}, naiveOptions, 4);
  EXPECT_LT(relativeDifference(structured->velocity(), naive->velocity()), 1e-9);
}

// The lagged Schur factor (AsyncOptions::KeptFactors::laggedSchur) solves each step's Schur system by
// iterative refinement to a relative residual of 1e-10, so its trajectory follows the
// rebuilt one: 1e-7 relative after 20 large, visibly nonlinear steps (the residual
// tolerance times the growth of perturbations over the run, with margin), with damping and
// both couplings. Some steps must actually have used the old factor: on this violent state
// (random displacements of 0.1 on a 1-long bar) conjugate gradients (stable coupling)
// converge within the limit on about a third of the steps, iterative refinement (paper's)
// on fewer; the others rebuild.
TEST(NonlinearAsync, LaggedSchurFollowsTheRebuiltStep) {
  for (const AsyncCoupling coupling : {AsyncCoupling::stable, AsyncCoupling::paper}) {
    AsyncOptions lagged = test::withCoupling(coupling);
    EXPECT_TRUE(lagged.keptFactors.laggedSchur);  // the default
    AsyncOptions rebuilt = test::withCoupling(coupling);
    rebuilt.keptFactors.laggedSchur = false;  // the paper's Algorithm 2: Z and H^{LL*} every step
    const auto [exact, approximate] = runSideBySide(rebuilt, lagged, 20);
    EXPECT_EQ(exact->runStats().laggedSteps, 0);
    EXPECT_LT(relativeDifference(approximate->displacement(), exact->displacement()), 1e-7);
    EXPECT_LT(relativeDifference(approximate->velocity(), exact->velocity()), 1e-7);
    const AsyncRunStats& stats = approximate->runStats();
    EXPECT_GE(stats.laggedSteps, coupling == AsyncCoupling::stable ? 5 : 1);
    EXPECT_LE(stats.largestSchurResidual, lagged.keptFactors.laggedSchurTolerance);
    EXPECT_GT(stats.schurIterations, 0);
  }
}

// The lagged factor turned with the body (AsyncOptions::KeptFactors::laggedSchurRotation, default on):
// the clamped bar swung about z (v = omega z x x, omega = 20 rad/s, no load), so that its
// stiff tip turns by tenths of a radian while the factor is kept. Turned and unturned runs
// both follow the rebuilt one (1e-7 relative after 30 steps, as above: both solve to the
// same residual tolerance), and the turned one needs fewer conjugate-gradient iterations
// and no more full rebuilds (Z computed), some of the rule's rebuilds being refreshes (the
// kept C_i turned, no Z): 50 iterations and 10 full rebuilds plus 10 refreshes against 63
// and 15 when written.
TEST(NonlinearAsync, TheLaggedFactorTurnedWithTheBodyIteratesLess) {
  test::TestSystem ts = makeCorotationalSystem(0.0, 0.0);
  ts.system.externalForce = nullptr;
  ts.u0.setZero();
  for (int v = 0; v < ts.mesh.numVertices(); ++v) {
    const Eigen::Vector3d x = ts.mesh.restPosition(v);
    ts.v0.segment<3>(3 * v) = 20.0 * Eigen::Vector3d(-x.y(), x.x(), 0.0);
  }
  ts.v0 = ts.system.freeDofs.expand(ts.system.freeDofs.restrict(ts.v0));  // clamped DOFs at rest
  const std::vector<AsyncRegion> regions{{"tip", test::verticesBeyond(ts.mesh, 0.75), 6}};
  AsyncOptions rebuiltOptions, unturnedOptions;
  rebuiltOptions.keptFactors.laggedSchur = false;
  unturnedOptions.keptFactors.laggedSchurRotation = false;
  std::vector<std::unique_ptr<AsyncBackwardEuler>> runs;
  for (const AsyncOptions& options : {rebuiltOptions, unturnedOptions, AsyncOptions{}}) {
    runs.push_back(std::make_unique<AsyncBackwardEuler>(ts.mesh, ts.system, 2e-3, regions, options));
    runs.back()->setState(ts.u0, ts.v0);
    for (int k = 0; k < 30; ++k) runs.back()->step();
  }
  const AsyncBackwardEuler& rebuilt = *runs[0];
  const AsyncBackwardEuler& unturned = *runs[1];
  const AsyncBackwardEuler& turned = *runs[2];
  for (const AsyncBackwardEuler* run : {&unturned, &turned}) {
    EXPECT_LT(relativeDifference(run->displacement(), rebuilt.displacement()), 1e-7);
    EXPECT_LT(relativeDifference(run->velocity(), rebuilt.velocity()), 1e-7);
    EXPECT_LE(run->runStats().largestSchurResidual, AsyncOptions{}.keptFactors.laggedSchurTolerance);
  }
  const long long unturnedRebuilds = unturned.runStats().steps - unturned.runStats().laggedSteps;
  const long long turnedRebuilds = turned.runStats().steps - turned.runStats().laggedSteps;
  EXPECT_LE(turnedRebuilds, unturnedRebuilds);
  EXPECT_GT(turned.runStats().laggedRefreshes, 0);
  EXPECT_EQ(unturned.runStats().laggedRefreshes, 0);
  EXPECT_LT(turned.runStats().schurIterations, unturned.runStats().schurIterations)
      << "rebuilds: turned " << turnedRebuilds << ", unturned " << unturnedRebuilds;
}

// At tiny amplitudes corotational forces are linear, so the nonlinear asynchronous step
// equals the linear one. The difference is second order in the amplitude (rotations of
// size |grad u| ~ 1e-6 here), so 1e-5 relative is a loose bound.
TEST(NonlinearAsync, TinyAmplitudesMatchTheLinearStep) {
  test::TestSystem linear = test::makeTestSystem(0.1, 1e-3);
  test::TestSystem corotational = makeCorotationalSystem(0.1, 1e-3);
  linear.system.externalForce = nullptr;  // the pull would drive amplitudes far from tiny
  corotational.system.externalForce = nullptr;
  std::vector<AsyncRegion> regions{{"tip", test::verticesBeyond(linear.mesh, 0.75), 5}};
  AsyncBackwardEuler a(linear.mesh, linear.system, 2e-3, regions);
  AsyncBackwardEuler b(corotational.mesh, corotational.system, 2e-3, regions);
  a.setState(1e-3 * linear.u0, 1e-3 * linear.v0);
  b.setState(1e-3 * linear.u0, 1e-3 * linear.v0);
  for (int k = 0; k < 5; ++k) {
    a.step();
    b.step();
  }
  EXPECT_LT(relativeDifference(a.displacement(), b.displacement()), 1e-5);
}

/// Rest positions rotated rigidly by angle about axis, as a displacement field.
Eigen::VectorXd rigidRotation(const TetMesh& mesh, double angle, const Eigen::Vector3d& axis) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  Eigen::VectorXd u(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v) u.segment<3>(3 * v) = R * mesh.restPosition(v) - mesh.restPosition(v);
  return u;
}

double maxEdgeStrain(const TetMesh& mesh, const Eigen::VectorXd& u) {
  double worst = 0.0;
  for (int e = 0; e < mesh.numElements(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        const int i = mesh.elements()(a, e), j = mesh.elements()(b, e);
        const double rest = (mesh.restPosition(i) - mesh.restPosition(j)).norm();
        const double now =
            (mesh.restPosition(i) + u.segment<3>(3 * i) - mesh.restPosition(j) - u.segment<3>(3 * j)).norm();
        worst = std::max(worst, std::abs(now - rest) / rest);
      }
  return worst;
}

// A large rigid rotation of the whole (unconstrained) mesh at rest stays exactly where it
// is (no elastic force, so no motion), and a spinning mesh keeps its shape far better than
// with linear forces, which inflate it.
TEST(NonlinearAsync, RigidRotationCausesNoDeformation) {
  test::TestSystem ts = makeCorotationalSystem(0.0, 0.0);
  ts.system.freeDofs = FreeDofs(ts.mesh.numDofs(), {});
  ts.system.externalForce = nullptr;
  std::vector<AsyncRegion> regions{{"tip", test::verticesBeyond(ts.mesh, 0.75), 4}};
  const Eigen::VectorXd rotated = rigidRotation(ts.mesh, 1.2, Eigen::Vector3d(1, 2, 3));
  AsyncBackwardEuler still(ts.mesh, ts.system, 2e-3, regions);
  still.setState(rotated, Eigen::VectorXd::Zero(ts.mesh.numDofs()));
  for (int k = 0; k < 10; ++k) still.step();
  // 1e-9: forces at a rigid rotation are zero to round-off (~1e-12 of E * area).
  EXPECT_LT(relativeDifference(still.displacement(), rotated), 1e-9);
  EXPECT_LT(still.velocity().lpNorm<Eigen::Infinity>(), 1e-9);

  // Spin about the bar's axis at 20 rad/s for 0.1 s (2 radians).
  const Eigen::Vector3d omega(20.0, 0.0, 0.0);
  Eigen::VectorXd spin(ts.mesh.numDofs());
  for (int v = 0; v < ts.mesh.numVertices(); ++v) spin.segment<3>(3 * v) = omega.cross(ts.mesh.restPosition(v));
  test::TestSystem linear = test::makeTestSystem(0.0, 0.0);
  linear.system.freeDofs = ts.system.freeDofs;
  linear.system.externalForce = nullptr;
  AsyncBackwardEuler spinning(ts.mesh, ts.system, 2e-3, regions);
  AsyncBackwardEuler spinningLinear(linear.mesh, linear.system, 2e-3, regions);
  spinning.setState(Eigen::VectorXd::Zero(ts.mesh.numDofs()), spin);
  spinningLinear.setState(Eigen::VectorXd::Zero(ts.mesh.numDofs()), spin);
  for (int k = 0; k < 50; ++k) {
    spinning.step();
    spinningLinear.step();
  }
  const double corotationalStrain = maxEdgeStrain(ts.mesh, spinning.displacement());
  const double linearStrain = maxEdgeStrain(ts.mesh, spinningLinear.displacement());
  EXPECT_GT(linearStrain, 0.1);  // linear FEM visibly inflates a rotated body
  EXPECT_LT(corotationalStrain, 0.1 * linearStrain);
}

// A body dropped on the ground comes to rest with small penetration and never gains
// energy after its first impact (energy = kinetic + elastic + gravitational + penalty).
TEST(NonlinearAsync, DroppedBodyRestsOnTheGround) {
  BoxMeshSpec spec;
  spec.origin = Eigen::Vector3d(0.0, 0.02, 0.0);
  spec.size = Eigen::Vector3d(0.3, 0.1, 0.1);
  spec.cells = Eigen::Vector3i(6, 2, 2);
  spec.material = Material{"soft", 1000.0, 2e5, 0.4};
  spec.regions.push_back(
      {"stiff", Eigen::Vector3d(0.2, -1, -1), Eigen::Vector3d(1, 1, 1), Material{"stiff", 500.0, 5e6, 0.3}});
  const auto mesh = std::make_shared<const TetMesh>(makeBoxMesh(spec));
  const Eigen::Vector3d g(0.0, -9.81, 0.0);
  PenaltyContactParameters parameters;
  parameters.stiffness = 2e3;
  parameters.damping = 5.0;
  auto contact = std::make_shared<PenaltyContact>(mesh->restPositions(), std::vector<ContactPlane>{ContactPlane{}},
                                                  std::vector<ContactSphere>{}, parameters);
  ProblemSettings settings = test::testSettings(ForceModelType::corotational);
  settings.gravity = g;
  const Problem problem(mesh, {}, settings, {}, contact);
  const Eigen::VectorXd gravity = problem.massMatrix() * g.replicate(mesh->numVertices(), 1);
  std::vector<AsyncRegion> regions{{"stiff", test::verticesBeyond(*mesh, 0.25), 4}};
  AsyncBackwardEuler async(problem.dynamicSystem(), 2e-3, regions);
  auto energy = [&]() {
    const Eigen::VectorXd& u = async.displacement();
    double penalty = 0.0;
    for (int v = 0; v < mesh->numVertices(); ++v) {
      const double depth = -(mesh->restPosition(v).y() + u[3 * v + 1]);
      if (depth > 0) penalty += 0.5 * parameters.stiffness * depth * depth;
    }
    return async.mechanicalEnergy() - gravity.dot(u) + penalty;
  };
  bool impacted = false;
  double afterImpact = 0.0, worstGain = 0.0;
  for (int k = 0; k < 1000; ++k) {  // 2 s
    async.step();
    const bool touching = contact->activeContacts(async.displacement()) > 0;
    if (touching && !impacted) {
      impacted = true;
      afterImpact = energy();
    }
    if (impacted) worstGain = std::max(worstGain, energy() - afterImpact);
  }
  ASSERT_TRUE(impacted);
  // Resting penetration m g / (k * contact vertices) = 3 kg * 9.81 / (2e3 * 21) = 7e-4.
  EXPECT_LT(contact->maxPenetration(async.displacement()), 2e-3);
  EXPECT_LT(async.velocity().lpNorm<Eigen::Infinity>(), 0.05);  // at rest
  // No gain beyond 1% of the energy at impact (explicit penalty forces can pump a little).
  EXPECT_LT(worstGain, 0.01 * std::abs(afterImpact) + 1e-9) << "energy at impact " << afterImpact;
}

}  // namespace
}  // namespace asyncfem
