// SPDX-License-Identifier: BSD-3-Clause
// The uncoupled multirate comparator: m = 1 is backward Euler at hL, S = everything is m
// backward Euler steps at hS, and for m > 1 it differs from the asynchronous method.
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/asyncIntegrator/uncoupledMultirate.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/integrator/registry.hpp>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "../common/testProblems.hpp"

namespace asyncfem {
namespace {

// The stiff-end bar of testProblems.hpp (fixed at x = 0, stiff light end x > 0.75) with a
// time-varying pull on its free face and a random initial state, so that every term of
// the step is exercised.
struct Bar : test::TestBody {
  using TestBody::TestBody;
  Eigen::VectorXd u0, v0;
  std::vector<int> stiffVertices;
};

Bar makeBar(double alpha, double beta) {
  Bar bar(test::stiffEndBarProblem(test::testSettings(ForceModelType::linear, alpha, beta)));
  const std::vector<int> pulled = bar.mesh.vertexSet("xmax");
  bar.system.externalForce = [pulled](double t, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& f) {
    for (const int v : pulled) f[3 * v + 1] -= 0.5 * std::cos(40.0 * t);
  };
  test::RandomState state = test::randomState(bar.system.freeDofs, 11, test::FixedDofDraws::skipped);
  bar.u0 = std::move(state.displacement);
  bar.v0 = std::move(state.velocity);
  bar.stiffVertices = bar.mesh.vertexSet("stiff");
  return bar;
}

double relativeDifference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).norm() / std::max({1e-300, a.norm(), b.norm()});
}

TEST(UncoupledMultirate, RatioOneIsBackwardEulerAtTheLargeStep) {
  // 1e-9 relative: the same equations solved by different factorizations (LU of the
  // compound matrix vs Cholesky), over 5 steps.
  for (const auto& [alpha, beta] : {std::pair{0.0, 0.0}, std::pair{0.3, 2e-3}}) {
    Bar bar = makeBar(alpha, beta);
    const double hL = 4e-3;
    UncoupledMultirate multirate(bar.system, hL, {{"stiff", bar.stiffVertices, 1}});
    BackwardEuler single(bar.system, hL);
    multirate.setState(bar.u0, bar.v0);
    single.setState(bar.u0, bar.v0);
    for (int s = 0; s < 5; ++s) {
      multirate.step();
      single.step();
    }
    EXPECT_LT(relativeDifference(multirate.displacement(), single.displacement()), 1e-9);
    EXPECT_LT(relativeDifference(multirate.velocity(), single.velocity()), 1e-9);
    EXPECT_EQ(multirate.name(), "multirate-uncoupled");
  }
}

TEST(UncoupledMultirate, EverythingFastIsBackwardEulerAtTheSmallStep) {
  // No L: the compound step is the first substep, the others follow alone: m single-rate
  // steps at hS (1e-9 relative).
  Bar bar = makeBar(0.3, 1e-3);
  std::vector<int> all;
  for (int v = 0; v < bar.mesh.numVertices(); ++v) all.push_back(v);
  const double hL = 8e-3;
  const int m = 4;
  UncoupledMultirate multirate(bar.system, hL, {{"all", all, m}});
  BackwardEuler single(bar.system, hL / m);
  multirate.setState(bar.u0, bar.v0);
  single.setState(bar.u0, bar.v0);
  for (int s = 0; s < 3; ++s) {
    multirate.step();
    for (int r = 0; r < m; ++r) single.step();
  }
  EXPECT_LT(relativeDifference(multirate.displacement(), single.displacement()), 1e-9);
  EXPECT_LT(relativeDifference(multirate.velocity(), single.velocity()), 1e-9);
}

TEST(UncoupledMultirate, DiffersFromAsyncForRatiosAboveOne) {
  Bar bar = makeBar(0.0, 0.0);
  const double hL = 8e-3;
  for (const int m : {2, 8}) {
    UncoupledMultirate multirate(bar.system, hL, {{"stiff", bar.stiffVertices, m}});
    AsyncBackwardEuler async(bar.system, hL, {{"stiff", bar.stiffVertices, m}});
    BackwardEuler fine(bar.system, hL / (16 * m));
    multirate.setState(bar.u0, bar.v0);
    async.setState(bar.u0, bar.v0);
    fine.setState(bar.u0, bar.v0);
    multirate.step();
    async.step();
    for (int k = 0; k < 16 * m; ++k) fine.step();
    const Eigen::VectorXd changeMultirate = multirate.displacement() - bar.u0;
    const Eigen::VectorXd changeAsync = async.displacement() - bar.u0;
    const Eigen::VectorXd changeFine = fine.displacement() - bar.u0;
    // The schemes differ at first order in the coupling: far above round-off (1e-9 of
    // the step's displacement change)...
    EXPECT_GT((changeMultirate - changeAsync).norm(), 1e-6 * changeAsync.norm()) << "m = " << m;
    // ...yet both are consistent first-order schemes: against backward Euler at hS / 16
    // their errors over the step are of the same size (within 3x; measured 1.15x at m = 8).
    EXPECT_LT((changeMultirate - changeFine).norm(), 3.0 * (changeAsync - changeFine).norm()) << "m = " << m;
    // Cost: one compound solve and m - 1 region solves per large step.
    EXPECT_EQ(multirate.stats().solvedRightHandSides, m);
    EXPECT_EQ(multirate.stats().factorizations, 2);
  }
}

// Registered by registerMultirateIntegrators() (which scenes use): built from its options
// on the beam generator's mesh pulled at the tip for 0.1 s, and async-only keys rejected
// by name.
TEST(UncoupledMultirate, IsRegisteredAndRejectsAsyncOnlyKeys) {
  BeamSpec spec;
  spec.cellsAlongLength = 5;
  const auto mesh = std::make_shared<const TetMesh>(makeBeamMesh(spec));
  const std::vector<int>& tip = mesh->vertexSet("tip");
  const Problem problem(mesh, mesh->vertexSet("root"), {},
                        {VertexLoad{tip, Eigen::Vector3d(0.0, -1.0 / static_cast<double>(tip.size()), 0.0), 0.0, 0.1}});
  IntegratorRegistry registry;
  registerMultirateIntegrators(registry);
  IntegratorContext context;
  context.mesh = mesh;
  context.system = problem.dynamicSystem();
  context.timestep = 0.01;
  context.frameRate = 50.0;
  context.sourceName = "multirate.json";
  nlohmann::json options = {{"regions", {{{"name", "tip"}, {"ratio", 4}, {"elementSets", {"tip"}}}}}};
  const std::unique_ptr<Integrator> integrator = registry.create("multirate-uncoupled", context, options);
  EXPECT_EQ(integrator->name(), "multirate-uncoupled");
  for (int k = 0; k < 2; ++k) integrator->step();  // one frame at 50 frames/s
  EXPECT_GT(integrator->displacement().norm(), 0.0);

  options["schur"] = "symmetric";
  try {
    registry.create("multirate-uncoupled", context, options);
    FAIL() << "expected a ValidationError";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("integrator.options.schur"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace asyncfem
