// SPDX-License-Identifier: BSD-3-Clause
// How "regions": "auto" decides, and what it costs: the pre-check that needs no modal solve
// where materials and element sizes leave no light or stiff part, and the modal check's one
// factorization where it is needed (docs/asynchronous-integrator.md, "Proposed regions").
#include <gtest/gtest.h>

#include <asyncfem/asyncIntegrator/regionProposal.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/modalAnalysis/lowestModes.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "regionProposalMeshes.hpp"

namespace asyncfem {
namespace {

// The frequency with the shape taken out: a regular tet's own frequency, inversely
// proportional to the edge length, the same for a flat tet with the same edges (whose
// element frequency is far higher), and proportional to the material's wave speed.
TEST(RegionProposalDecision, SizeFrequencyIsTheRegularTetsAtTheElementsEdgeLength) {
  Eigen::Matrix<double, 3, 4> regular;
  regular << 1, 1, -1, -1, 1, -1, 1, -1, 1, -1, -1, 1;  // edge 2 sqrt(2)
  const Material rubber{"rubber", 1000.0, 1e6, 0.45};
  EXPECT_NEAR(elementSizeFrequency(regular, rubber), elementMaxFrequency(regular, rubber),
              1e-12 * elementMaxFrequency(regular, rubber));
  EXPECT_NEAR(elementSizeFrequency(2.0 * regular, rubber), 0.5 * elementSizeFrequency(regular, rubber),
              1e-12 * elementSizeFrequency(regular, rubber));
  const Material light{"light", 10.0, 1e6, 0.45};  // 100x lighter: 10x the wave speed
  EXPECT_NEAR(elementSizeFrequency(regular, light), 10.0 * elementSizeFrequency(regular, rubber),
              1e-10 * elementSizeFrequency(regular, light));
  // A sliver: a unit square's diagonals 1e-3 apart (edges 1, 1, 1, 1, sqrt 2, sqrt 2).
  Eigen::Matrix<double, 3, 4> sliver;
  sliver << 0, 1, 1, 0, 0, 0, 1, 1, 0, 1e-3, 0, 1e-3;
  // Its edges are 1 and sqrt 2 to a relative 1e-6 (the offsets of 1e-3 lengthen them).
  const double rms = std::sqrt((4.0 + 2.0 * 2.0) / 6.0);
  EXPECT_NEAR(elementSizeFrequency(sliver, rubber), elementSizeFrequency(regular, rubber) * std::sqrt(8.0) / rms,
              2e-6 * elementSizeFrequency(sliver, rubber));
  EXPECT_GT(elementMaxFrequency(sliver, rubber), 100.0 * elementSizeFrequency(sliver, rubber));
}

// One material on a mesh made by isosurface stuffing (the shipped drop, 4,507 tets, with
// every element rubber): its cut elements near the surface are marked by the element
// criterion (omega_e above 3x the median) for their shape, but no element is fast by its
// material and size, so the pre-check withdraws the regions: no cost check, no modal solve.
TEST(RegionProposalDecision, OneMaterialMeshIsDecidedByThePrecheckWithoutAModalSolve) {
  const TetMesh mesh = test::withOneMaterial(readMesh(std::string(ASYNCFEM_MODELS_DIR) + "/drop/drop.veg"),
                                             Material{"rubber", 1000.0, 1e6, 0.45});
  const FreeDofs freeDofs = test::clampedBelow(mesh, mesh.restPositions().row(2).minCoeff() + 0.02);
  const VibrationMatrices matrices = vibrationMatrices(mesh, MassType::consistent);
  RegionProposalOptions options;
  options.largeTimestep = 0.01;
  options.modalCheck = true;  // as the scene path runs it
  const RegionProposal proposal = proposeRegions(mesh, freeDofs, options, matrices.stiffness, matrices.mass);
  EXPECT_EQ(proposal.decidedBy, RegionProposalPath::precheck) << regionProposalSummary(proposal);
  EXPECT_TRUE(proposal.regions.empty());
  EXPECT_FALSE(proposal.precheckWithdrawnRegions.empty());
  EXPECT_FALSE(proposal.modalReport.has_value());
  EXPECT_EQ(proposal.modalFactorizations, 0);
  EXPECT_EQ(proposal.modalSolves, 0);
  EXPECT_FALSE(proposal.cost.evaluated);
  const RegionProposalPrecheck& check = proposal.precheck;
  ASSERT_TRUE(check.evaluated);
  EXPECT_TRUE(check.shapeOnly);
  EXPECT_GT(check.markedElements, 0);  // the element criterion did mark elements
  EXPECT_EQ(check.sizeMarkedElements, 0);
  EXPECT_EQ(check.waveSpeedSpread, 1.0);
  EXPECT_LE(check.maxSizeFrequencyRatio, options.relativeThreshold);
  EXPECT_GT(check.sizeSpread, 1.0);
  const std::string summary = regionProposalSummary(proposal);
  EXPECT_NE(summary.find("no fast region kept, single-rate at hL: the pre-check found no light or stiff part"),
            std::string::npos)
      << summary;
  EXPECT_NE(summary.find("no modal solve"), std::string::npos) << summary;
  EXPECT_NE(summary.find("by the pre-check)"), std::string::npos) << summary;

  // Without the pre-check the same regions go to the cost check and the modal check, as
  // before it; the modal solve then takes one factorization, whatever the mode count.
  RegionProposalOptions checked = options;
  checked.precheck = false;
  checked.costCheck = false;  // reach the modal check whatever the cost model says
  checked.maxModalCount = 40;
  const RegionProposal modal = proposeRegions(mesh, freeDofs, checked, matrices.stiffness, matrices.mass);
  EXPECT_EQ(modal.decidedBy, RegionProposalPath::modalCheck);
  EXPECT_FALSE(modal.precheck.evaluated);
  ASSERT_TRUE(modal.modalReport.has_value());
  EXPECT_EQ(modal.modalFactorizations, 1);
  EXPECT_GE(modal.modalSolves, static_cast<int>(modal.modalReport->modes.size()));
  EXPECT_EQ(modal.withdrawnRegions.size(), proposal.precheckWithdrawnRegions.size());
}

// Two materials: the antenna's rod (rho 50 on a block of rho 1000, the same E) is 4.5x
// faster by its material, so the pre-check leaves the decision to the modal check, which
// keeps the rod with the ratio its modes need, exactly as without the pre-check.
TEST(RegionProposalDecision, TwoMaterialsStillFindTheLightPart) {
  const TetMesh mesh = test::antennaOnBlock();
  const FreeDofs freeDofs = test::clampedBelow(mesh, 1e-12);
  const VibrationMatrices matrices = vibrationMatrices(mesh, MassType::consistent);
  RegionProposalOptions options = test::antennaModalOptions();
  options.costCheck = false;  // as RegionProposal.ModalCheckKeepsARegionWhoseModesLiveInIt
  const RegionProposal proposal = proposeRegions(mesh, freeDofs, options, matrices.stiffness, matrices.mass);
  ASSERT_TRUE(proposal.precheck.evaluated);
  EXPECT_FALSE(proposal.precheck.shapeOnly);
  EXPECT_GT(proposal.precheck.sizeMarkedElements, 0);
  EXPECT_NEAR(proposal.precheck.waveSpeedSpread, std::sqrt(20.0), 1e-9);
  EXPECT_EQ(proposal.decidedBy, RegionProposalPath::modalCheck);
  ASSERT_EQ(proposal.regions.size(), 1u) << regionProposalSummary(proposal);
  ASSERT_TRUE(proposal.modalReport.has_value());
  EXPECT_EQ(proposal.modalReport->verdict, ModalVerdict::asyncKeepsModes);
  EXPECT_EQ(proposal.modalFactorizations, 1);
  for (int v : proposal.regions[0].region.vertices) EXPECT_GE(mesh.restPosition(v).z(), 0.1 - 1e-12);

  RegionProposalOptions before = options;
  before.precheck = false;
  before.modalTolerance = 1e-10;  // lowestModes()'s default, as the check ran before
  const RegionProposal old = proposeRegions(mesh, freeDofs, before, matrices.stiffness, matrices.mass);
  ASSERT_EQ(old.regions.size(), 1u);
  EXPECT_EQ(proposal.regions[0].region.vertices, old.regions[0].region.vertices);
  EXPECT_EQ(proposal.regions[0].region.ratio, old.regions[0].region.ratio);
  EXPECT_EQ(proposal.regions[0].modeForRatio, old.regions[0].modeForRatio);
  ASSERT_EQ(proposal.modalReport->modes.size(), old.modalReport->modes.size());
  for (std::size_t k = 0; k < old.modalReport->modes.size(); ++k) {
    const ModeInRegions& a = proposal.modalReport->modes[k];
    const ModeInRegions& b = old.modalReport->modes[k];
    EXPECT_NEAR(a.omega, b.omega, 1e-6 * b.omega + 1e-9) << "mode " << k;
    EXPECT_NEAR(a.fastShare, b.fastShare, 1e-4) << "mode " << k;
    EXPECT_EQ(a.keepable, b.keepable) << "mode " << k;
  }
  options.modalTolerance = 0.0;
  EXPECT_THROW(proposeRegions(mesh, freeDofs, options, matrices.stiffness, matrices.mass), ValidationError);
}

}  // namespace
}  // namespace asyncfem
