// SPDX-License-Identifier: BSD-3-Clause
// AsyncBackwardEuler::setUp(partition) between steps, as run-time regions will call it.
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <cstdio>
#include <string>

#include "asyncTestSystem.hpp"

namespace asyncfem {
namespace {

// After setUp() with another partition, the steps equal those of an integrator built with
// that partition from the same state at the same time, bit for bit: the state is
// synchronous at a large-step boundary, setUp() drops every block and factor of the old
// partition, and both integrators then do the same operations in the same order.
TEST(AsyncSetUp, NewPartitionEqualsAFreshIntegratorFromTheSameState) {
  const test::TestSystem ts = test::makeTestSystem(0.3, 2e-3);
  const double hL = 5e-3;
  const std::vector<AsyncRegion> before{{"tip", test::verticesBeyond(ts.mesh, 0.75), 4}};
  const std::vector<AsyncRegion> after{{"half", test::verticesBeyond(ts.mesh, 0.5), 8}};
  for (const AsyncCoupling coupling : {AsyncCoupling::stable, AsyncCoupling::paper}) {
    AsyncBackwardEuler moving(ts.mesh, ts.system, hL, before, test::withCoupling(coupling));
    moving.setState(ts.u0, ts.v0);
    for (int k = 0; k < 3; ++k) moving.step();
    AsyncBackwardEuler fresh(ts.mesh, ts.system, hL, after, test::withCoupling(coupling));
    fresh.setState(moving.displacement(), moving.velocity(), moving.time());
    moving.setUp(RegionPartition(ts.mesh, ts.system.freeDofs, after));
    ASSERT_EQ(moving.partition().numRegions(), 1);
    EXPECT_EQ(moving.partition().ratio(0), 8);
    for (int k = 0; k < 3; ++k) {
      moving.step();
      fresh.step();
    }
    EXPECT_EQ(moving.time(), fresh.time());
    EXPECT_EQ((moving.displacement() - fresh.displacement()).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((moving.velocity() - fresh.velocity()).cwiseAbs().maxCoeff(), 0.0);
  }
}

// Z from the region's modes (one dense eigendecomposition of (K^SS, M^SS), a scalar
// recurrence per mode) gives the steps Z by m |I| substitutions gives, up to round-off:
// undamped and Rayleigh-damped, both couplings, a small and a large ratio. Tolerance 1e-10
// relative over four steps: the two paths round differently (the eigenvectors carry
// about 1e-14 |K| |M^-1| of error), measured 1.2e-13 (recorded as largestDifference). The
// run statistics name the path.
TEST(AsyncSetUp, ZFromModesEqualsZBySubstitution) {
  const double hL = 5e-3;
  double largest = 0.0;
  for (const double alpha : {0.0, 0.3})
    for (const AsyncCoupling coupling : {AsyncCoupling::stable, AsyncCoupling::paper})
      for (const int ratio : {3, 30}) {
        const test::TestSystem ts = test::makeTestSystem(alpha, alpha > 0 ? 2e-3 : 0.0);
        const std::vector<AsyncRegion> regions{{"tip", test::verticesBeyond(ts.mesh, 0.75), ratio}};
        AsyncOptions substitution = test::withCoupling(coupling), modes = substitution;
        substitution.zSolve = ZSolve::substitution;
        modes.zSolve = ZSolve::modes;
        AsyncBackwardEuler substituted(ts.mesh, ts.system, hL, regions, substitution);
        AsyncBackwardEuler modal(ts.mesh, ts.system, hL, regions, modes);
        substituted.setState(ts.u0, ts.v0);
        modal.setState(ts.u0, ts.v0);
        for (int k = 0; k < 4; ++k) {
          substituted.step();
          modal.step();
        }
        const std::string where = "alpha " + std::to_string(alpha) + " ratio " + std::to_string(ratio);
        largest = std::max({largest, test::relativeDifference(modal.displacement(), substituted.displacement()),
                            test::relativeDifference(modal.velocity(), substituted.velocity())});
        EXPECT_LT(test::relativeDifference(modal.displacement(), substituted.displacement()), 1e-10) << where;
        EXPECT_LT(test::relativeDifference(modal.velocity(), substituted.velocity()), 1e-10) << where;
        EXPECT_GT(test::relativeDifference(modal.displacement(), ts.u0), 1e-3) << where;  // it moved
        EXPECT_EQ(modal.runStats().zModalRegions, 1) << where;
        EXPECT_EQ(substituted.runStats().zModalRegions, 0) << where;
        EXPECT_EQ(modal.runStats().zColumns, 0) << where;  // no substitution at all
        bool named = false;
        for (const std::string& line : modal.report().lines)
          named = named || line.find("1 region(s) from their modes") != std::string::npos;
        EXPECT_TRUE(named) << where;
      }
  char text[32];
  std::snprintf(text, sizeof(text), "%.2e", largest);
  RecordProperty("largestDifference", text);
}

// Switching back and forth leaves nothing of an earlier partition behind: after tip, half
// and tip again, the step equals that of a fresh tip integrator from the same state.
TEST(AsyncSetUp, PartitionsCanAlternate) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 0.0);
  const double hL = 5e-3;
  const std::vector<AsyncRegion> tip{{"tip", test::verticesBeyond(ts.mesh, 0.75), 4}};
  const std::vector<AsyncRegion> half{{"half", test::verticesBeyond(ts.mesh, 0.5), 2}};
  AsyncBackwardEuler moving(ts.mesh, ts.system, hL, tip);
  moving.setState(ts.u0, ts.v0);
  moving.step();
  moving.setUp(RegionPartition(ts.mesh, ts.system.freeDofs, half));
  moving.step();
  AsyncBackwardEuler fresh(ts.mesh, ts.system, hL, tip);
  fresh.setState(moving.displacement(), moving.velocity(), moving.time());
  moving.setUp(RegionPartition(ts.mesh, ts.system.freeDofs, tip));
  moving.step();
  fresh.step();
  EXPECT_EQ((moving.displacement() - fresh.displacement()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((moving.velocity() - fresh.velocity()).cwiseAbs().maxCoeff(), 0.0);
}

// A partition of another mesh or other free DOFs is refused with the counts that differ.
TEST(AsyncSetUp, APartitionOfAnotherSystemIsAnError) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 0.0);
  AsyncBackwardEuler async(ts.mesh, ts.system, 5e-3, {{"tip", test::verticesBeyond(ts.mesh, 0.75), 4}});
  const FreeDofs allFree = FreeDofs::fromFixedVertices(ts.mesh.numVertices(), {});
  try {
    async.setUp(RegionPartition(ts.mesh, allFree, {{"tip", test::verticesBeyond(ts.mesh, 0.75), 4}}));
    FAIL() << "expected a ValidationError";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("free DOFs"), std::string::npos) << error.what();
  }
}

// A system without its mesh cannot be partitioned: the error says how to give one.
TEST(AsyncSetUp, ASystemWithoutAMeshIsAnError) {
  test::TestSystem ts = test::makeTestSystem(0.0, 0.0);
  ts.system.mesh = nullptr;
  try {
    AsyncBackwardEuler async(ts.system, 5e-3, {{"tip", test::verticesBeyond(ts.mesh, 0.75), 4}});
    FAIL() << "expected a ValidationError";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("no mesh"), std::string::npos) << error.what();
  }
}

// AsyncOptions::Processes::largeSystemSolver: the factory is called at each set-up with L's DOFs, its
// solver is given the assembled H^{LL*}, and the run equals the default (CHOLMOD) one to
// the rounding of two direct factorizations (Eigen's LDLT here; kappa eps over a few steps,
// 1e-10 of the largest displacement), before and after a new partition.
TEST(AsyncSetUp, AnExternalLargeSystemSolverSolvesLsSystem) {
  const test::TestSystem ts = test::makeTestSystem(0.3, 2e-3);
  const double hL = 5e-3;
  const std::vector<AsyncRegion> tip{{"tip", test::verticesBeyond(ts.mesh, 0.75), 4}};
  const std::vector<AsyncRegion> half{{"half", test::verticesBeyond(ts.mesh, 0.5), 8}};
  std::vector<std::size_t> largeSizes;
  AsyncOptions options;
  std::vector<std::vector<std::vector<int>>> interfaces;
  options.processes.largeSystemSolver = [&largeSizes, &interfaces](const std::vector<int>& largeDofs,
                                                                   const std::vector<std::vector<int>>& interfaceDofs) {
    largeSizes.push_back(largeDofs.size());
    interfaces.push_back(interfaceDofs);
    return makeSparseSolver(SolverKind::eigenLDLT);
  };
  AsyncBackwardEuler external(ts.mesh, ts.system, hL, tip, options);
  AsyncBackwardEuler reference(ts.mesh, ts.system, hL, tip);
  for (AsyncBackwardEuler* integrator : {&external, &reference}) {
    integrator->setState(ts.u0, ts.v0);
    for (int k = 0; k < 3; ++k) integrator->step();
    integrator->setUp(RegionPartition(ts.mesh, ts.system.freeDofs, half));
    for (int k = 0; k < 3; ++k) integrator->step();
  }
  ASSERT_EQ(largeSizes.size(), 2u);
  EXPECT_GT(largeSizes[0], largeSizes[1]);  // the half region leaves L fewer DOFs than the tip
  EXPECT_EQ(largeSizes[1], external.partition().largeDofs().size());
  // Each call names every region's interface DOFs, which are DOFs of L.
  ASSERT_EQ(interfaces.size(), 2u);
  ASSERT_EQ(interfaces[1].size(), 1u);
  EXPECT_EQ(interfaces[1][0], external.partition().interfaceDofs(0));
  EXPECT_FALSE(interfaces[0][0].empty());
  EXPECT_NE(interfaces[0][0], interfaces[1][0]);
  const double scale = reference.displacement().cwiseAbs().maxCoeff();
  EXPECT_GT(scale, 0.0);
  EXPECT_LE((external.displacement() - reference.displacement()).cwiseAbs().maxCoeff(), 1e-10 * scale);
  // The paper's coupling gives an unsymmetric H^{LL*}: refused with an external solver.
  options.coupling = AsyncCoupling::paper;
  EXPECT_THROW(AsyncBackwardEuler(ts.mesh, ts.system, hL, tip, options), ValidationError);
}

}  // namespace
}  // namespace asyncfem
