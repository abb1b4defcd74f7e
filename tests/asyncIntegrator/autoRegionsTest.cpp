// SPDX-License-Identifier: BSD-3-Clause
#include "asyncTestSystem.hpp"

#include <asyncfem/asyncIntegrator/autoRegions.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

namespace asyncfem {
namespace {

// The element bound is >= the assembled system's highest frequency (element eigenvalue
// inequality), checked against a dense generalized eigen-solve with lumped mass.
TEST(AutoRegions, ElementFrequenciesBoundTheSystem) {
  const test::TestSystem ts = test::makeTestSystem(0, 0);
  MatrixAssembler assembler(ts.mesh);
  const Eigen::MatrixXd K = Eigen::MatrixXd(linearStiffnessMatrix(ts.mesh, assembler));
  const Eigen::MatrixXd M = Eigen::MatrixXd(massMatrix(ts.mesh, assembler, MassType::lumped));
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eigen(K, M, Eigen::EigenvaluesOnly);
  const double systemOmega = std::sqrt(eigen.eigenvalues().maxCoeff());
  const double bound = elementMaxFrequencies(ts.mesh).maxCoeff();
  EXPECT_GE(bound, systemOmega * (1 - 1e-10));
  // ... and not absurdly loose (a factor 4 would make the proposals useless).
  EXPECT_LT(bound, 4 * systemOmega);
}

TEST(AutoRegions, StiffTipBecomesOneFastRegionMeetingTheTarget) {
  const test::TestSystem ts = test::makeTestSystem(0, 0);
  const Eigen::VectorXd omega = elementMaxFrequencies(ts.mesh);
  // Choose hL so the soft part meets the target and the stiff tip does not.
  double softMax = 0, stiffMax = 0;
  for (int e = 0; e < ts.mesh.numElements(); ++e) {
    double& bucket = ts.mesh.elementMaterial(e).name == "stiff" ? stiffMax : softMax;
    bucket = std::max(bucket, omega[e]);
  }
  ASSERT_GT(stiffMax, 2 * softMax);
  AutoRegionOptions options;
  options.targetOmegaH = 1.0;
  options.largeTimestep = 0.9 / softMax;
  options.growLayers = 0;
  const AutoRegionProposal proposal = suggestRegions(ts.mesh, ts.system.freeDofs, options);
  ASSERT_EQ(proposal.regions.size(), 1u);
  const ProposedRegion& r = proposal.regions[0];
  EXPECT_GE(r.region.ratio, 2);
  EXPECT_LE(r.maxFrequency * options.largeTimestep / r.region.ratio, options.targetOmegaH * (1 + 1e-12));
  EXPECT_LE(proposal.largeRegionMaxFrequency * options.largeTimestep, options.targetOmegaH);
  for (int v : r.region.vertices) EXPECT_GE(ts.mesh.restPosition(v).x(), 0.75 - 1e-12);
  EXPECT_GT(r.numInterfaceDofs, 0);
  // The proposal is a valid partition the integrator accepts.
  AsyncBackwardEuler async(ts.mesh, ts.system, options.largeTimestep, proposal.asyncRegions());
  async.step();
}

TEST(AutoRegions, GrowingAddsRingsAndKeepsOneRegion) {
  const test::TestSystem ts = test::makeTestSystem(0, 0);
  AutoRegionOptions options;
  options.targetOmegaH = 1.0;
  const Eigen::VectorXd omega = elementMaxFrequencies(ts.mesh);
  options.largeTimestep = 1.5 / omega.minCoeff();
  options.growLayers = 0;
  const auto none = suggestRegions(ts.mesh, ts.system.freeDofs, options);
  options.growLayers = 1;
  const auto grown = suggestRegions(ts.mesh, ts.system.freeDofs, options);
  ASSERT_FALSE(none.regions.empty());
  ASSERT_FALSE(grown.regions.empty());
  EXPECT_GE(grown.regions[0].region.vertices.size(), none.regions[0].region.vertices.size());
}

TEST(AutoRegions, NothingProposedWhenEverythingMeetsTheTarget) {
  const test::TestSystem ts = test::makeTestSystem(0, 0);
  AutoRegionOptions options;
  options.largeTimestep = 0.5 / elementMaxFrequencies(ts.mesh).maxCoeff();
  options.targetOmegaH = 1.0;
  EXPECT_TRUE(suggestRegions(ts.mesh, ts.system.freeDofs, options).regions.empty());
  options.largeTimestep = -1;
  EXPECT_THROW(suggestRegions(ts.mesh, ts.system.freeDofs, options), ValidationError);
}

// Relative mode (the default): the stiff, light tip is about an order of magnitude
// "faster" than the median element, so it alone becomes a region, whatever hL is.
TEST(AutoRegions, RelativeModeFindsTheStiffPartAtAnyTimestep) {
  const test::TestSystem ts = test::makeTestSystem(0, 0);
  double targetPerTimestep = -1;  // the relative target is proportional to hL
  for (double hL : {1e-4, 1e-2, 1.0}) {
    AutoRegionOptions options;
    options.largeTimestep = hL;
    options.growLayers = 0;
    const AutoRegionProposal proposal = suggestRegions(ts.mesh, ts.system.freeDofs, options);
    ASSERT_EQ(proposal.regions.size(), 1u) << "hL " << hL;
    for (int v : proposal.regions[0].region.vertices) EXPECT_GE(ts.mesh.restPosition(v).x(), 0.75 - 1e-12);
    EXPECT_GE(proposal.regions[0].region.ratio, 2);
    if (targetPerTimestep < 0) targetPerTimestep = proposal.targetOmegaH / hL;
    EXPECT_NEAR(proposal.targetOmegaH / hL, targetPerTimestep, 1e-12 * targetPerTimestep);
  }
}

}  // namespace
}  // namespace asyncfem
