// SPDX-License-Identifier: BSD-3-Clause
// Backward Euler with the corotational force model (the refactoring path).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/problem/problem.hpp>
#include <utility>
#include <vector>

#include "testSystems.hpp"

namespace asyncfem::test {
namespace {

/// The rubber bar of makeBar() with corotational forces, fixedVertices held.
DynamicSystem corotationalSystem(const BarBody& bar, std::vector<int> fixedVertices, TangentKind tangent) {
  ProblemSettings settings = testSettings(ForceModelType::corotational);
  settings.tangent = tangent;
  return Problem(bar.problem->sharedMesh(), std::move(fixedVertices), settings).dynamicSystem();
}

// A free-floating bar rotated rigidly by 40 degrees and released at rest feels no
// elastic force, so backward Euler leaves it where it is (linear FEM would pull it back
// and shrink it). 1e-9 relative: the rotations come from SVDs, accurate to ~1e-14, and
// the system matrix has condition number ~1e5.
TEST(CorotationalBackwardEuler, RigidRotationStaysPut) {
  const BarBody bar = makeBar();
  const DynamicSystem system = corotationalSystem(bar, {}, TangentKind::simple);
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 2.0, 0.5).normalized()).matrix();
  Eigen::VectorXd u(bar.mesh.numDofs());
  for (int vertex = 0; vertex < bar.mesh.numVertices(); ++vertex) {
    const Eigen::Vector3d x = bar.mesh.restPosition(vertex);
    u.segment<3>(3 * vertex) = rotation * x - x;
  }
  IntegratorOptions exact;  // one factorization per step, as counted below
  exact.reuseFactor = false;
  BackwardEuler integrator(system, 1e-2, exact);
  integrator.setState(u, Eigen::VectorXd::Zero(u.size()));
  for (int k = 0; k < 10; ++k) integrator.step();
  EXPECT_LE((integrator.displacement() - u).norm(), 1e-9 * u.norm());
  EXPECT_LE(integrator.velocity().norm(), 1e-9 * u.norm() / 1e-2);
  EXPECT_EQ(integrator.stats().factorizations, 10);
}

// At small amplitude corotational and linear FEM agree to first order in the
// displacement: the relative difference of the trajectories is O(amplitude).
TEST(CorotationalBackwardEuler, MatchesLinearAtSmallDeformation) {
  const BarBody bar = makeBar();
  const DynamicSystem system = corotationalSystem(bar, bar.mesh.vertexSet("xmin"), TangentKind::simple);
  Eigen::VectorXd u0 = Eigen::VectorXd::Zero(bar.mesh.numDofs());
  for (int vertex = 0; vertex < bar.mesh.numVertices(); ++vertex) {
    const double x = bar.mesh.restPosition(vertex).x();
    u0[(3 * vertex) + 2] = 1e-5 * x * x;  // a slight bend
  }
  BackwardEuler corotational(system, 1e-3);
  BackwardEuler linear(bar.system, 1e-3);
  corotational.setState(u0, Eigen::VectorXd::Zero(u0.size()));
  linear.setState(u0, Eigen::VectorXd::Zero(u0.size()));
  for (int k = 0; k < 20; ++k) {
    corotational.step();
    linear.step();
  }
  EXPECT_LE((corotational.displacement() - linear.displacement()).norm(), 1e-3 * linear.displacement().norm());
  for (int dof = 0; dof < bar.mesh.numDofs(); ++dof) {
    if (bar.freeDofs.isFixed(dof)) {
      ASSERT_EQ(corotational.displacement()[dof], 0.0);
    }
  }
}

// With the exact tangent Newton converges on the corotational backward Euler equations.
TEST(CorotationalBackwardEuler, NewtonConvergesWithExactTangent) {
  const BarBody bar = makeBar();
  const DynamicSystem system = corotationalSystem(bar, bar.mesh.vertexSet("xmin"), TangentKind::exact);
  Eigen::VectorXd u0 = Eigen::VectorXd::Zero(bar.mesh.numDofs());
  for (int vertex = 0; vertex < bar.mesh.numVertices(); ++vertex) {
    const double x = bar.mesh.restPosition(vertex).x();
    u0[(3 * vertex) + 2] = 0.3 * x * x;  // a large bend
  }
  IntegratorOptions options;
  options.maxIterations = 30;
  options.tolerance = 1e-9;
  BackwardEuler integrator(system, 5e-3, options);
  integrator.setState(u0, Eigen::VectorXd::Zero(u0.size()));
  integrator.step();
  EXPECT_LE(integrator.lastRelativeResidual(), 1e-9);
  EXPECT_GT(integrator.lastIterations(), 1);
  EXPECT_LT(integrator.lastIterations(), 30);
}

}  // namespace
}  // namespace asyncfem::test
