// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/factory.hpp>
#include <string>

#include "testSystems.hpp"

namespace asyncfem::test {
namespace {

TEST(IntegratorFactory, CreatesEveryNamedIntegrator) {
  const BarBody body = makeBar(MassType::lumped);
  for (const std::string& name : integratorNames()) {
    std::unique_ptr<Integrator> integrator = makeIntegrator(name, body.system, 1e-6);
    ASSERT_NE(integrator, nullptr);
    EXPECT_EQ(integrator->name(), name);
    EXPECT_DOUBLE_EQ(integrator->timestep(), 1e-6);
    integrator->step();
    EXPECT_DOUBLE_EQ(integrator->time(), 1e-6);
  }
}

TEST(IntegratorFactory, UnknownNameListsValidNames) {
  const BarBody body = makeBar();
  try {
    makeIntegrator("runge-kutta", body.system, 1e-3);
    FAIL() << "expected Error";
  } catch (const Error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("runge-kutta"), std::string::npos) << message;
    for (const std::string& name : integratorNames()) EXPECT_NE(message.find(name), std::string::npos) << message;
  }
}

TEST(IntegratorFactory, ImplicitMethodsAreUnconditionallyStable) {
  const BarBody body = makeBar();
  EXPECT_TRUE(std::isinf(makeIntegrator("backward-euler", body.system, 1.0)->stableTimestepEstimate()));
  EXPECT_TRUE(std::isinf(makeIntegrator("trapezoidal", body.system, 1.0)->stableTimestepEstimate()));
}

}  // namespace
}  // namespace asyncfem::test
