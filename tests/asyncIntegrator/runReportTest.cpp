// SPDX-License-Identifier: BSD-3-Clause
// What the multirate integrators say in their RunReport and through MultirateIntegrator:
// drivers print it (summaries, resumes) and act on it (the step-growth check), so each
// item is asserted for the configurations that set it and those that do not.
#include <gtest/gtest.h>

#include <asyncfem/asyncIntegrator/uncoupledMultirate.hpp>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/integrator/multirateIntegrator.hpp>

#include "asyncTestSystem.hpp"

namespace asyncfem {
namespace {

std::vector<AsyncRegion> tipRegion(const TetMesh& mesh) { return {{"tip", test::verticesBeyond(mesh, 0.75), 4}}; }

// Only the paper's coupling may gain energy, so only it asks drivers for the growth check.
TEST(AsyncRunReport, OnlyThePaperCouplingMayGainEnergy) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 0.0);
  AsyncBackwardEuler stable(ts.mesh, ts.system, 5e-3, tipRegion(ts.mesh), test::withCoupling(AsyncCoupling::stable));
  AsyncBackwardEuler paper(ts.mesh, ts.system, 5e-3, tipRegion(ts.mesh), test::withCoupling(AsyncCoupling::paper));
  EXPECT_FALSE(stable.report().mayGainEnergy);
  EXPECT_TRUE(paper.report().mayGainEnergy);
}

// Linear forces are factored at set-up: the factors are reported before the first step,
// and the summary lines name the set-up.
TEST(AsyncRunReport, LinearFactorsAreReportedFromTheSetUp) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 0.0);
  AsyncBackwardEuler async(ts.mesh, ts.system, 5e-3, tipRegion(ts.mesh));
  const RunReport report = async.report();
  EXPECT_GT(report.factorNonZeros, 0);
  EXPECT_EQ(report.factorNonZeros, async.factorNonZeros());
  ASSERT_GE(report.lines.size(), 2u);
  EXPECT_EQ(report.lines[0], "async step solver: structured Schur (each region coupled only to L)");
  EXPECT_NE(report.lines[1].find("async set-up"), std::string::npos) << report.lines[1];
  EXPECT_TRUE(report.resumeCaveat.empty()) << report.resumeCaveat;
}

// The lagged H^{LL*} factor (nonlinear forces, the default) is not in a checkpoint: a
// resumed run refactors, so the report says the frames match to the Schur tolerance only.
// Without the lag, or with linear forces, a resume is bit-identical and nothing is said.
TEST(AsyncRunReport, TheLaggedSchurFactorIsAResumeCaveat) {
  test::TestSystem ts = test::makeTestSystem(0.0, 0.0);
  ts.system.forceModel = std::make_shared<CorotationalLinearFEM>(ts.mesh, TangentKind::simple);
  AsyncBackwardEuler lagged(ts.mesh, ts.system, 5e-3, tipRegion(ts.mesh));
  EXPECT_NE(lagged.report().resumeCaveat.find("laggedSchur"), std::string::npos) << lagged.report().resumeCaveat;
  AsyncOptions rebuilt;
  rebuilt.keptFactors.laggedSchur = false;
  AsyncBackwardEuler exact(ts.mesh, ts.system, 5e-3, tipRegion(ts.mesh), rebuilt);
  EXPECT_TRUE(exact.report().resumeCaveat.empty()) << exact.report().resumeCaveat;
}

// Multirate integrators answer region queries through MultirateIntegrator; single-rate
// ones have none, and the free functions say so without a cast.
TEST(AsyncRunReport, RegionQueriesGoThroughTheMultirateInterface) {
  const test::TestSystem ts = test::makeTestSystem(0.0, 0.0);
  const std::vector<int> tip = test::verticesBeyond(ts.mesh, 0.75);
  AsyncBackwardEuler async(ts.mesh, ts.system, 5e-3, tipRegion(ts.mesh));
  UncoupledMultirate uncoupled(ts.mesh, ts.system, 5e-3, tipRegion(ts.mesh));
  BackwardEuler single(ts.system, 5e-3);
  for (const Integrator* multirate :
       {static_cast<const Integrator*>(&async), static_cast<const Integrator*>(&uncoupled)}) {
    ASSERT_NE(multirate->multirate(), nullptr);
    const std::vector<RegionSummary> regions = regionSummaries(*multirate);
    ASSERT_EQ(regions.size(), 1u);
    EXPECT_EQ(regions[0].name, "tip");
    EXPECT_EQ(regions[0].ratio, 4);
    EXPECT_EQ(regions[0].vertices, static_cast<int>(tip.size()));
    EXPECT_EQ(regionOfVertex(*multirate, tip.front()), 0);
    EXPECT_EQ(regionOfVertex(*multirate, 0), -1);  // vertex 0 is at x = 0, in L
  }
  EXPECT_EQ(single.multirate(), nullptr);
  EXPECT_TRUE(regionSummaries(single).empty());
  EXPECT_EQ(regionOfVertex(single, tip.front()), -1);
  EXPECT_GT(single.report().factorNonZeros, 0);
}

}  // namespace
}  // namespace asyncfem
