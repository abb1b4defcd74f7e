// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <limits>
#include <string>

#include "testSystems.hpp"

namespace asyncfem::test {
namespace {

bool contains(const std::vector<std::string>& list, const std::string& item) {
  return std::find(list.begin(), list.end(), item) != list.end();
}

// A deterministic state that excites every mode.
Eigen::VectorXd wiggle(int size, double amplitude, double phase) {
  Eigen::VectorXd x(size);
  for (int i = 0; i < size; ++i) x[i] = amplitude * std::sin((1.3 * i) + phase);
  return x;
}

TEST(BackwardEuler, LinearModelFactorsOnceAndSkipsDamping) {
  BarBody body = makeBar();
  BackwardEuler integrator(body.system, 1e-3);
  integrator.setState(wiggle(body.system.numDofs(), 1e-3, 0.0), Eigen::VectorXd::Zero(body.system.numDofs()));
  for (int k = 0; k < 50; ++k) integrator.step();
  EXPECT_EQ(integrator.stats().factorizations, 1);
  EXPECT_EQ(integrator.stats().steps, 50);
  EXPECT_EQ(integrator.stats().solvedRightHandSides, 50);
  EXPECT_TRUE(contains(integrator.stats().skipped, "damping matrix (alpha = beta = 0)"));
  EXPECT_TRUE(contains(integrator.stats().skipped, "refactorization (constant system matrix)"));

  // A new timestep costs exactly one more numeric factorization.
  integrator.setTimestep(2e-3);
  for (int k = 0; k < 10; ++k) integrator.step();
  EXPECT_EQ(integrator.stats().factorizations, 2);
}

TEST(BackwardEuler, DampedModelDoesNotSkipDamping) {
  BarBody body = makeBar(MassType::consistent, 0.1, 1e-4);
  BackwardEuler integrator(body.system, 1e-3);
  EXPECT_FALSE(contains(integrator.stats().skipped, "damping matrix (alpha = beta = 0)"));
}

// The same steps built from dense Eigen matrices, with damping and a time-dependent
// load. Tolerance 1e-10 relative: both sides are backward-stable solves of a system with
// condition number ~1e4 (M + h D + h^2 K at this h), so they agree to ~1e-12.
TEST(BackwardEuler, MatchesDenseStep) {
  const double alpha = 0.3, beta = 2e-4, h = 2e-3;
  BarBody body = makeBar(MassType::consistent, alpha, beta);
  body.system.externalForce = [](double t, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& f) {
    for (Eigen::Index i = 2; i < f.size(); i += 3) f[i] -= 5.0 * (1.0 + std::sin(40.0 * t));
  };
  BackwardEuler integrator(body.system, h);
  const int n = body.system.numDofs();
  integrator.setState(wiggle(n, 1e-3, 0.2), wiggle(n, 1e-2, 1.1), 0.1);

  const Eigen::MatrixXd K = denseFree(body.stiffness, body.freeDofs);
  const Eigen::MatrixXd M = denseFree(body.mass, body.freeDofs);
  const Eigen::MatrixXd D = alpha * M + beta * K;
  const Eigen::MatrixXd A = M + h * D + h * h * K;
  const Eigen::LDLT<Eigen::MatrixXd> factor(A);
  Eigen::VectorXd u = body.freeDofs.restrict(integrator.displacement());
  Eigen::VectorXd v = body.freeDofs.restrict(integrator.velocity());
  double t = integrator.time();
  for (int k = 0; k < 5; ++k) {
    Eigen::VectorXd fullForce = Eigen::VectorXd::Zero(n);
    body.system.externalForce(t + h, {}, {}, fullForce);
    const Eigen::VectorXd f = body.freeDofs.restrict(fullForce);
    const Eigen::VectorXd dv = factor.solve(h * (f - K * u - D * v - h * K * v));
    v += dv;
    u += h * v;
    t += h;
    integrator.step();
    const Eigen::VectorXd uc = body.freeDofs.restrict(integrator.displacement());
    const Eigen::VectorXd vc = body.freeDofs.restrict(integrator.velocity());
    EXPECT_LE((uc - u).norm(), 1e-10 * u.norm()) << "step " << k;
    EXPECT_LE((vc - v).norm(), 1e-10 * v.norm()) << "step " << k;
    EXPECT_DOUBLE_EQ(integrator.time(), t);
  }
}

// Backward Euler on an undamped free linear vibration: E_{k+1} <= E_k. (Exactly:
// E_{k+1} - E_k = -(dv^T M dv + h^2 v_{k+1}^T K v_{k+1}) / 2 <= 0.) The slack 1e-12 E_k
// covers round-off in the energy sums.
TEST(BackwardEuler, NeverIncreasesEnergyOfFreeVibration) {
  BarBody body = makeBar();
  const int n = body.system.numDofs();
  for (double h : {1e-4, 1e-3, 1e-2}) {
    BackwardEuler integrator(body.system, h);
    integrator.setState(wiggle(n, 1e-3, 0.0), wiggle(n, 1e-1, 0.5));
    double previous = integrator.mechanicalEnergy();
    ASSERT_GT(previous, 0.0);
    for (int k = 0; k < 200; ++k) {
      integrator.step();
      const double energy = integrator.mechanicalEnergy();
      ASSERT_LE(energy, previous * (1.0 + 1e-12)) << "h " << h << " step " << k;
      previous = energy;
    }
  }
}

TEST(BackwardEuler, FixedDofsStayExactlyZero) {
  BarBody body = makeBar(MassType::consistent, 0.1, 1e-4);
  // The load pushes on every DOF, fixed ones included.
  body.system.externalForce = [](double, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& f) {
    f.setConstant(3.0);
  };
  BackwardEuler integrator(body.system, 1e-3);
  integrator.setState(Eigen::VectorXd::Constant(body.system.numDofs(), 1e-3),
                      Eigen::VectorXd::Constant(body.system.numDofs(), 1e-2));
  for (int k = 0; k < 20; ++k) {
    integrator.step();
    for (int dof = 0; dof < body.system.numDofs(); ++dof) {
      if (!body.freeDofs.isFixed(dof)) continue;
      ASSERT_EQ(integrator.displacement()[dof], 0.0);
      ASSERT_EQ(integrator.velocity()[dof], 0.0);
    }
  }
  EXPECT_GT(integrator.displacement().lpNorm<Eigen::Infinity>(), 0.0);
}

TEST(BackwardEuler, NonFiniteStateThrowsAndKeepsPreviousState) {
  BarBody body = makeBar();
  const int badDof = body.freeDofs.freeToFull()[10];
  body.system.externalForce = [badDof](double t, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& f) {
    if (t > 0.0025) f[badDof] = std::numeric_limits<double>::quiet_NaN();
  };
  BackwardEuler integrator(body.system, 1e-3);
  integrator.step();
  integrator.step();
  const Eigen::VectorXd u = integrator.displacement();
  const Eigen::VectorXd v = integrator.velocity();
  try {
    integrator.step();
    FAIL() << "expected NumericalError";
  } catch (const NumericalError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("backward-euler"), std::string::npos) << message;
    EXPECT_NE(message.find("time 0.003"), std::string::npos) << message;
    EXPECT_NE(message.find("vertex"), std::string::npos) << message;
  }
  EXPECT_EQ(integrator.displacement(), u);
  EXPECT_EQ(integrator.velocity(), v);
  EXPECT_DOUBLE_EQ(integrator.time(), 0.002);
}

/// Linear FEM plus a cubic spring on every DOF: f_int(u) = K u + c u.^3,
/// K(u) = K + diag(3 c u.^2), energy u^T K u / 2 + c sum u^4 / 4. Not linear, so the
/// integrators take the refactoring path.
class CubicForceModel final : public ForceModel {
 public:
  CubicForceModel(Eigen::SparseMatrix<double> stiffness, double cubic)
      : stiffness_(std::move(stiffness)), cubic_(cubic) {}
  int numDofs() const override { return static_cast<int>(stiffness_.rows()); }
  bool isLinear() const override { return false; }
  Eigen::SparseMatrix<double> createStiffnessMatrix() const override { return stiffness_; }
  void internalForces(const Eigen::VectorXd& u, Eigen::VectorXd& f) override {
    f = stiffness_ * u + cubic_ * u.array().cube().matrix();
  }
  void tangentStiffness(const Eigen::VectorXd& u, Eigen::SparseMatrix<double>& k) override {
    k = stiffness_;
    for (int i = 0; i < k.rows(); ++i) k.coeffRef(i, i) += 3.0 * cubic_ * u[i] * u[i];
  }
  double elasticEnergy(const Eigen::VectorXd& u) override {
    return 0.5 * u.dot(stiffness_ * u) + 0.25 * cubic_ * u.array().pow(4).sum();
  }

 private:
  Eigen::SparseMatrix<double> stiffness_;
  double cubic_;
};

// Residual of the nonlinear backward Euler equations (alpha = beta = 0, no load) at the
// integrator's new state, relative to the linearized right-hand side.
double nonlinearResidual(ForceModel& model, const BarBody& body, const Eigen::VectorXd& u0, const Eigen::VectorXd& v0,
                         const Eigen::VectorXd& u1, const Eigen::VectorXd& v1, double h) {
  Eigen::VectorXd f1, f0;
  model.internalForces(u1, f1);
  model.internalForces(u0, f0);
  Eigen::SparseMatrix<double> k0 = model.createStiffnessMatrix();
  model.tangentStiffness(u0, k0);
  const Eigen::VectorXd residual = body.freeDofs.restrict(body.mass * (v1 - v0) + h * f1);
  const Eigen::VectorXd linearizedRhs = body.freeDofs.restrict(h * (-f0 - h * (k0 * v0)));
  return residual.norm() / linearizedRhs.norm();
}

TEST(BackwardEuler, NewtonIterationsReduceTheNonlinearResidual) {
  BarBody body = makeBar();
  // c u^3 is ~30% of K u at displacements of 0.02 (K's diagonal is ~1e5 here).
  auto model = std::make_shared<CubicForceModel>(body.stiffness, 1e8);
  body.system.forceModel = model;
  const int n = body.system.numDofs();
  Eigen::VectorXd u0 = wiggle(n, 0.02, 0.3), v0 = wiggle(n, 0.5, 1.0);
  body.freeDofs.expand(body.freeDofs.restrict(u0)).swap(u0);
  body.freeDofs.expand(body.freeDofs.restrict(v0)).swap(v0);
  const double h = 2e-3;

  // The exact path (one factorization per Newton iteration), whose counts are asserted.
  IntegratorOptions linearized;
  linearized.reuseFactor = false;
  BackwardEuler once(body.system, h, linearized);
  once.setState(u0, v0);
  once.step();
  EXPECT_EQ(once.lastIterations(), 1);
  EXPECT_EQ(once.stats().factorizations, 1);
  const double linearizedResidual = nonlinearResidual(*model, body, u0, v0, once.displacement(), once.velocity(), h);

  IntegratorOptions newton = linearized;
  newton.maxIterations = 20;
  newton.tolerance = 1e-10;
  BackwardEuler iterated(body.system, h, newton);
  iterated.setState(u0, v0);
  iterated.step();
  const double newtonResidual =
      nonlinearResidual(*model, body, u0, v0, iterated.displacement(), iterated.velocity(), h);
  EXPECT_GT(iterated.lastIterations(), 1);
  EXPECT_LT(iterated.lastIterations(), 20);
  EXPECT_LE(iterated.lastRelativeResidual(), 1e-10);
  EXPECT_EQ(iterated.stats().factorizations, iterated.lastIterations());
  // The independently computed residual agrees (it differs only by round-off).
  EXPECT_LE(newtonResidual, 1e-9);
  EXPECT_GT(linearizedResidual, 1e3 * newtonResidual);
  EXPECT_GT(linearizedResidual, 1e-6);

  // The nonlinear path keeps the analysis but refactors every step.
  for (int k = 0; k < 4; ++k) once.step();
  EXPECT_EQ(once.stats().factorizations, 5);
  EXPECT_FALSE(contains(once.stats().skipped, "refactorization (constant system matrix)"));
}

TEST(BackwardEuler, RejectsBadOptions) {
  BarBody body = makeBar();
  IntegratorOptions options;
  options.maxIterations = 0;
  EXPECT_THROW(BackwardEuler(body.system, 1e-3, options), ValidationError);
  EXPECT_THROW(BackwardEuler(body.system, -1.0), ValidationError);
}

}  // namespace
}  // namespace asyncfem::test
