// SPDX-License-Identifier: BSD-3-Clause
// The asynchronous integrator's nonlinear path (linearize once per large step, element
// tangents for the coupling) with a hyperelastic force model.
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/problem/problem.hpp>
#include <vector>

#include "../common/testProblems.hpp"

namespace asyncfem {
namespace {

// The rubber cantilever of testProblems.hpp at 8 x 2 x 2 cubes (1 x 0.2 x 0.2, x = 0 fixed),
// neo-Hookean, swinging at v_y = 2 x (displacements of about 0.1 within a few steps:
// visibly nonlinear).
struct Bar : test::TestBody {
  using TestBody::TestBody;
  std::vector<int> tip;  // vertices with x > 0.75
  Eigen::VectorXd velocity;
};

Bar makeBar(double alpha, double beta) {
  Bar bar(test::rubberBarProblem(test::testSettings(ForceModelType::neoHookean, alpha, beta), {8, 2, 2}));
  bar.velocity = Eigen::VectorXd::Zero(bar.mesh.numDofs());
  for (int v = 0; v < bar.mesh.numVertices(); ++v) {
    const double x = bar.mesh.restPosition(v).x();
    if (x > 0.0) bar.velocity[(3 * v) + 1] = 2.0 * x;
    if (x > 0.75) bar.tip.push_back(v);
  }
  return bar;
}

double relativeDifference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).norm() / std::max(a.norm(), b.norm());
}

// m = 1: the asynchronous step is the linearized backward Euler step at hL. Tolerance
// 1e-9: the same equations solved through different factorizations.
TEST(AsyncHyperelastic, RatioOneEqualsBackwardEuler) {
  Bar bar = makeBar(0.2, 1e-3);
  const double h = 5e-3;
  AsyncBackwardEuler async(bar.system, h, {{"tip", bar.tip, 1}});
  BackwardEuler single(bar.system, h);
  const Eigen::VectorXd rest = Eigen::VectorXd::Zero(bar.mesh.numDofs());
  async.setState(rest, bar.velocity);
  single.setState(rest, bar.velocity);
  for (int k = 0; k < 10; ++k) {
    async.step();
    single.step();
  }
  ASSERT_GT(single.displacement().cwiseAbs().maxCoeff(), 0.05);  // large enough to be nonlinear
  EXPECT_LT(relativeDifference(async.displacement(), single.displacement()), 1e-9);
  EXPECT_LT(relativeDifference(async.velocity(), single.velocity()), 1e-9);
}

// m = 4 in the tip: the structured solve equals the naive reference (1e-9, as above), and
// the motion stays close to single-rate backward Euler at the large step (the substeps
// change it by the time discretization error, well below 10 % over 10 steps).
TEST(AsyncHyperelastic, StructuredEqualsNaiveWithSubsteps) {
  Bar bar = makeBar(0.2, 1e-3);
  const double h = 5e-3;
  std::vector<AsyncRegion> regions{{"tip", bar.tip, 4}};
  AsyncOptions naiveOptions;
  naiveOptions.method = AsyncSolveMethod::naive;
  AsyncBackwardEuler structured(bar.system, h, regions);
  AsyncBackwardEuler naive(bar.system, h, regions, naiveOptions);
  BackwardEuler single(bar.system, h);
  const Eigen::VectorXd rest = Eigen::VectorXd::Zero(bar.mesh.numDofs());
  structured.setState(rest, bar.velocity);
  naive.setState(rest, bar.velocity);
  single.setState(rest, bar.velocity);
  for (int k = 0; k < 10; ++k) {
    structured.step();
    naive.step();
    single.step();
  }
  EXPECT_LT(relativeDifference(structured.velocity(), naive.velocity()), 1e-9);
  EXPECT_LT(relativeDifference(structured.displacement(), single.displacement()), 0.1);
}

}  // namespace
}  // namespace asyncfem
