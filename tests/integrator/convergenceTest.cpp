// SPDX-License-Identifier: BSD-3-Clause
// Observed convergence order of the single-rate integrators against the exact modal
// solution of a small linear bar.
#include <gtest/gtest.h>

#include <asyncfem/integrator/factory.hpp>
#include <asyncfem/integrator/stableTimestep.hpp>
#include <cstdio>
#include <string>
#include <vector>

#include "testSystems.hpp"

namespace asyncfem::test {
namespace {

struct ConvergenceSetup {
  BarBody body;
  Eigen::MatrixXd stiffness, mass;
  std::unique_ptr<ModalReference> reference;
  Eigen::VectorXd u0, v0;  // free
};

// Initial state in the span of the two lowest modes (the two bending modes of the bar),
// so that every excited mode has h omega << 1 at the timesteps used and the error is in
// its asymptotic regime.
ConvergenceSetup makeSetup(MassType massType) {
  ConvergenceSetup s{makeBar(massType), {}, {}, nullptr, {}, {}};
  s.stiffness = denseFree(s.body.stiffness, s.body.freeDofs);
  s.mass = denseFree(s.body.mass, s.body.freeDofs);
  s.reference = std::make_unique<ModalReference>(s.stiffness, s.mass);
  const Eigen::MatrixXd& modes = s.reference->modes();
  s.u0 = 0.01 * (modes.col(0) / modes.col(0).norm()) + 0.004 * (modes.col(1) / modes.col(1).norm());
  s.v0 = s.reference->omega()[1] * 0.005 * (modes.col(1) / modes.col(1).norm());
  return s;
}

// Error at time T (relative to the exact displacement's norm) for N steps of size T / N.
double finalError(const ConvergenceSetup& s, const std::string& name, int steps, double endTime,
                  const IntegratorOptions& options = {}) {
  const double h = endTime / steps;
  std::unique_ptr<Integrator> integrator = makeIntegrator(name, s.body.system, h, options);
  integrator->setState(s.body.freeDofs.expand(s.u0), s.body.freeDofs.expand(s.v0));
  for (int k = 0; k < steps; ++k) integrator->step();
  const Eigen::VectorXd exact = s.reference->displacement(s.u0, s.v0, integrator->time());
  const Eigen::VectorXd computed = s.body.freeDofs.restrict(integrator->displacement());
  return (computed - exact).norm() / exact.norm();
}

// The fitted slope is exact only as h -> 0: at the largest h used here the next term of
// the error expansion changes it by O(h omega) <~ 0.1. 0.25 leaves room for that and
// is still far from the neighbouring orders (a first-order method cannot pass as second).
constexpr double orderTolerance = 0.25;

double observedOrder(const ConvergenceSetup& s, const std::string& name, double endTime,
                     const std::vector<int>& stepCounts, const IntegratorOptions& options = {}) {
  std::vector<double> timesteps, errors;
  for (int steps : stepCounts) {
    timesteps.push_back(endTime / steps);
    errors.push_back(finalError(s, name, steps, endTime, options));
  }
  const double order = fittedOrder(timesteps, errors);
  std::printf("%s: errors", name.c_str());
  for (double error : errors) std::printf(" %.3e", error);
  std::printf(" -> observed order %.3f\n", order);
  return order;
}

TEST(IntegratorConvergence, BackwardEulerIsFirstOrder) {
  const ConvergenceSetup s = makeSetup(MassType::consistent);
  // One period of the lowest mode. Backward Euler's relative error per mode is about
  // h omega^2 T / 2 (amplitude decay); the coarsest step keeps it near 0.05.
  const double endTime = 2.0 * M_PI / s.reference->omega()[0];
  const double omega = s.reference->omega()[1];
  const int first = static_cast<int>(std::ceil(omega * omega * endTime * endTime / 0.1));
  const double order =
      observedOrder(s, "backward-euler", endTime, {first, 2 * first, 4 * first, 8 * first, 16 * first});
  EXPECT_NEAR(order, 1.0, orderTolerance);
}

TEST(IntegratorConvergence, TrapezoidalIsSecondOrder) {
  const ConvergenceSetup s = makeSetup(MassType::consistent);
  const double endTime = 2.0 * M_PI / s.reference->omega()[0];
  const double omega = s.reference->omega()[1];
  const int first = static_cast<int>(std::ceil(endTime * omega / 0.2));
  const double order = observedOrder(s, "trapezoidal", endTime, {first, 2 * first, 4 * first, 8 * first});
  EXPECT_NEAR(order, 2.0, orderTolerance);
}

TEST(IntegratorConvergence, CentralDifferencesIsSecondOrder) {
  for (MassType massType : {MassType::consistent, MassType::lumped}) {
    const ConvergenceSetup s = makeSetup(massType);
    const double endTime = 2.0 * M_PI / s.reference->omega()[0];
    IntegratorOptions options;
    options.maxFrequency = estimateMaxFrequency(s.body.mesh, massType);
    // Start at half the stable step: every step count keeps h omega_max < 2.
    const int first = static_cast<int>(std::ceil(endTime / (0.5 * stableTimestepFromFrequency(options.maxFrequency))));
    const double order =
        observedOrder(s, "central-differences", endTime, {first, 2 * first, 4 * first, 8 * first}, options);
    EXPECT_NEAR(order, 2.0, orderTolerance) << (massType == MassType::lumped ? "lumped" : "consistent");
  }
}

TEST(IntegratorConvergence, SymplecticEulerIsFirstOrder) {
  const ConvergenceSetup s = makeSetup(MassType::lumped);
  const double endTime = 2.0 * M_PI / s.reference->omega()[0];
  IntegratorOptions options;
  options.maxFrequency = estimateMaxFrequency(s.body.mesh, MassType::lumped);
  const int first = static_cast<int>(std::ceil(endTime / (0.5 * stableTimestepFromFrequency(options.maxFrequency))));
  const double order = observedOrder(s, "symplectic-euler", endTime, {first, 2 * first, 4 * first, 8 * first}, options);
  EXPECT_NEAR(order, 1.0, orderTolerance);
}

}  // namespace
}  // namespace asyncfem::test
