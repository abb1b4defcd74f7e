// SPDX-License-Identifier: BSD-3-Clause
// Central differences and symplectic Euler: stable-timestep estimate and check, mass
// handling, numerical failure, fixed DOFs.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/centralDifferences.hpp>
#include <asyncfem/integrator/stableTimestep.hpp>
#include <asyncfem/integrator/symplecticEuler.hpp>
#include <limits>
#include <string>

#include "testSystems.hpp"

namespace asyncfem::test {
namespace {

double trueMaxFrequency(const BarBody& body) {
  const ModalReference modes(denseFree(body.stiffness, body.freeDofs), denseFree(body.mass, body.freeDofs));
  return modes.omega().maxCoeff();
}

// The element-wise bound must never be below the true omega_max (that would allow an
// unstable timestep); the ratio shows it is not absurdly loose either.
TEST(StableTimestep, ElementBoundIsAboveTrueMaxFrequency) {
  for (MassType massType : {MassType::consistent, MassType::lumped}) {
    for (const Eigen::Vector3i& cells : {Eigen::Vector3i(4, 1, 1), Eigen::Vector3i(3, 2, 2)}) {
      const BarBody body = makeBar(massType, 0.0, 0.0, cells);
      const double exact = trueMaxFrequency(body);
      const double bound = estimateMaxFrequency(body.mesh, massType);
      EXPECT_GE(bound, exact);
      EXPECT_LE(bound, 4.0 * exact);
    }
  }
}

TEST(StableTimestep, MatrixEstimateWithLumpedMassIsAnUpperBound) {
  const BarBody body = makeBar(MassType::lumped);
  const double exact = trueMaxFrequency(body);
  CentralDifferences integrator(body.system, 1e-6);
  EXPECT_GE(integrator.maxFrequency(), exact);
  EXPECT_DOUBLE_EQ(integrator.stableTimestepEstimate(), 2.0 / integrator.maxFrequency());
}

TEST(StableTimestep, MatrixEstimateWithConsistentMassIsCloseFromAbove) {
  const BarBody body = makeBar(MassType::consistent);
  const double exact = trueMaxFrequency(body);
  CentralDifferences integrator(body.system, 1e-6);
  EXPECT_GE(integrator.maxFrequency(), exact);
  EXPECT_LE(integrator.maxFrequency(), 1.1 * exact);
}

TEST(CentralDifferences, RefusesTimestepAboveEstimateUnlessForced) {
  const BarBody body = makeBar(MassType::lumped);
  IntegratorOptions options;
  options.maxFrequency = estimateMaxFrequency(body.mesh, MassType::lumped);
  const double limit = stableTimestepFromFrequency(options.maxFrequency);
  try {
    CentralDifferences integrator(body.system, 1.5 * limit, options);
    FAIL() << "expected ValidationError";
  } catch (const ValidationError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("exceeds the estimated stable timestep"), std::string::npos) << message;
    EXPECT_NE(message.find("of central differences"), std::string::npos) << message;
    // It names what a user can change: no utility has a --force flag.
    EXPECT_NE(message.find("integrator.options.force: true"), std::string::npos) << message;
    EXPECT_EQ(message.find("--force"), std::string::npos) << message;
  }
  // Also when the timestep is changed later; the old one stays.
  CentralDifferences integrator(body.system, 0.5 * limit, options);
  EXPECT_THROW(integrator.setTimestep(2.0 * limit), ValidationError);
  EXPECT_DOUBLE_EQ(integrator.timestep(), 0.5 * limit);

  options.force = true;
  CentralDifferences forced(body.system, 1.5 * limit, options);
  forced.setState(Eigen::VectorXd::Constant(body.system.numDofs(), 1e-4), Eigen::VectorXd::Zero(body.system.numDofs()));
  for (int k = 0; k < 3; ++k) forced.step();
  EXPECT_EQ(forced.stats().steps, 3);
}

TEST(SymplecticEuler, RefusesTimestepAboveEstimate) {
  const BarBody body = makeBar(MassType::lumped);
  IntegratorOptions options;
  options.maxFrequency = estimateMaxFrequency(body.mesh, MassType::lumped);
  const double limit = stableTimestepFromFrequency(options.maxFrequency);
  try {
    SymplecticEuler integrator(body.system, 1.01 * limit, options);
    FAIL() << "expected ValidationError";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("of symplectic Euler"), std::string::npos) << error.what();
  }
  EXPECT_NO_THROW(SymplecticEuler(body.system, 0.99 * limit, options));
}

TEST(CentralDifferences, LumpedMassSkipsFactorization) {
  const BarBody lumped = makeBar(MassType::lumped);
  CentralDifferences diagonal(lumped.system, 1e-6);
  EXPECT_EQ(diagonal.stats().factorizations, 0);
  const BarBody consistent = makeBar(MassType::consistent);
  CentralDifferences factored(consistent.system, 1e-6);
  EXPECT_EQ(factored.stats().factorizations, 1);
  for (int k = 0; k < 10; ++k) factored.step();
  EXPECT_EQ(factored.stats().factorizations, 1);
}

// Without damping, v_{k+1/2} form equals the three-term recurrence
// u_{k+1} - 2 u_k + u_{k-1} = h^2 M^{-1} (-K u_k).
TEST(CentralDifferences, MatchesThreeTermRecurrence) {
  const BarBody body = makeBar(MassType::consistent);
  const Eigen::MatrixXd K = denseFree(body.stiffness, body.freeDofs);
  const Eigen::MatrixXd M = denseFree(body.mass, body.freeDofs);
  const double h = 1e-5;
  CentralDifferences integrator(body.system, h);
  const int n = body.system.numDofs();
  Eigen::VectorXd u0(n);
  for (int i = 0; i < n; ++i) u0[i] = 1e-3 * std::cos(0.9 * i);
  integrator.setState(u0, Eigen::VectorXd::Zero(n));
  std::vector<Eigen::VectorXd> u{body.freeDofs.restrict(integrator.displacement())};
  for (int k = 0; k < 6; ++k) {
    integrator.step();
    u.push_back(body.freeDofs.restrict(integrator.displacement()));
  }
  const Eigen::LDLT<Eigen::MatrixXd> mass(M);
  for (std::size_t k = 1; k + 1 < u.size(); ++k) {
    const Eigen::VectorXd expected = 2.0 * u[k] - u[k - 1] + h * h * mass.solve(-K * u[k]);
    EXPECT_LE((u[k + 1] - expected).norm(), 1e-10 * u[k + 1].norm()) << "step " << k;
  }
}

TEST(SymplecticEuler, NonFiniteStateNamesTheDofAndKeepsPreviousState) {
  BarBody body = makeBar(MassType::lumped);
  const int badDof = body.freeDofs.freeToFull()[7];
  body.system.externalForce = [badDof](double t, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& f) {
    if (t > 1.5e-6) f[badDof] = std::numeric_limits<double>::infinity();
  };
  SymplecticEuler integrator(body.system, 1e-6);
  integrator.step();
  integrator.step();
  const Eigen::VectorXd u = integrator.displacement(), v = integrator.velocity();
  const double t = integrator.time();
  try {
    integrator.step();
    FAIL() << "expected NumericalError";
  } catch (const NumericalError& error) {
    // With a diagonal mass the infinity stays on its DOF, so the message names it.
    const std::string message = error.what();
    const std::string coordinate = badDof % 3 == 0 ? "x" : (badDof % 3 == 1 ? "y" : "z");
    EXPECT_NE(message.find("DOF " + std::to_string(badDof) + " (vertex " + std::to_string(badDof / 3) +
                           ", coordinate " + coordinate + ")"),
              std::string::npos)
        << message;
    EXPECT_NE(message.find("time 0.000003"), std::string::npos) << message;
  }
  EXPECT_EQ(integrator.displacement(), u);
  EXPECT_EQ(integrator.velocity(), v);
  EXPECT_EQ(integrator.time(), t);
}

TEST(ExplicitIntegrators, FixedDofsStayExactlyZero) {
  BarBody body = makeBar(MassType::consistent, 0.5, 1e-6);
  body.system.externalForce = [](double, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& f) {
    f.setConstant(1.0);
  };
  CentralDifferences central(body.system, 1e-6);
  SymplecticEuler symplectic(body.system, 1e-6);
  for (int k = 0; k < 20; ++k) {
    central.step();
    symplectic.step();
  }
  for (int dof = 0; dof < body.system.numDofs(); ++dof) {
    if (!body.freeDofs.isFixed(dof)) continue;
    ASSERT_EQ(central.displacement()[dof], 0.0);
    ASSERT_EQ(central.velocity()[dof], 0.0);
    ASSERT_EQ(symplectic.displacement()[dof], 0.0);
    ASSERT_EQ(symplectic.velocity()[dof], 0.0);
  }
}

}  // namespace
}  // namespace asyncfem::test
