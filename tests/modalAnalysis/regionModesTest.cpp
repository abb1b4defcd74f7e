// SPDX-License-Identifier: BSD-3-Clause
// Modal-mass shares of fast regions, their exact sums over all modes, and the verdicts of
// the region report on a scene where async wins and on the default beam where it does not.
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/modalAnalysis/regionModes.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <filesystem>
#include <sstream>
#include <string>

#include "modalTestSystem.hpp"

namespace asyncfem {
namespace {

using testing::denseModes;
using testing::modalSystem;

// 3 x 2 x 2 cells (48 vertices), clamped at x = 0: 108 free DOFs, every mode computed densely.
TetMesh tinyBox() { return testing::boxMesh(Eigen::Vector3d(1.5, 1.0, 0.8), Eigen::Vector3i(3, 2, 2)); }

// The count lowest modes of a beam clamped at its root, reported for its "tip" vertex set
// with m = 8, hL = 1/120 and 30 frames/s; table receives the printed report.
RegionModeReport tipReport(const TetMesh& mesh, int count, std::string& table) {
  const auto system = modalSystem(mesh, mesh.vertexSet("root"), MassType::consistent);
  const ModalResult modes = testing::lowestModesOf(system, count);
  RegionModeReport report =
      analyseRegionModes(modes, system.mass, {{"tip", mesh.vertexSet("tip"), 8}}, 1.0 / 120.0, 30.0);
  std::ostringstream out;
  printRegionModeReport(out, report);
  table = out.str();
  return report;
}

// Free DOFs of the given vertices (global ids, ascending).
std::vector<int> freeDofsOf(const FreeDofs& freeDofs, const std::vector<int>& vertices) {
  std::vector<int> dofs;
  for (int v : vertices)
    for (int c = 0; c < 3; ++c)
      if (!freeDofs.isFixed(3 * v + c)) dofs.push_back(3 * v + c);
  std::sort(dofs.begin(), dofs.end());
  return dofs;
}

// Over all modes Phi (M_ff-orthonormal: Phi^T M_ff Phi = I, so Phi Phi^T = M_ff^{-1}),
//   sum_j phi_{j,S}^T M^{SS} phi_{j,S} = trace(M^{SS} (M_ff^{-1})^{SS}),
// which is exactly |S| (free DOFs in S) for a lumped (diagonal) mass.
TEST(RegionModes, SharesOverAllModesSumToTraceIdentity) {
  const TetMesh mesh = tinyBox();
  const std::vector<int> region = mesh.vertexSet("xmax");
  for (const MassType massType : {MassType::lumped, MassType::consistent}) {
    const auto system = modalSystem(mesh, mesh.vertexSet("xmin"), massType);
    const ModalResult all = denseModes(system);
    const RegionModeReport report = analyseRegionModes(all, system.mass, {{"end", region, 4}}, 0.01, 30.0);
    ASSERT_EQ(report.modes.size(), static_cast<std::size_t>(system.freeDofs.numFree()));
    double sum = 0.0;
    for (const ModeInRegions& mode : report.modes) {
      // phi_S^T M^{SS} phi_S >= 0 as M^{SS} is positive definite; <= 1 holds for a
      // lumped mass (phi^T M phi = 1 is then a sum of non-negative per-DOF terms). A
      // consistent mass couples S to L, and the cross term can push a share above 1.
      EXPECT_GE(mode.fastShare, -1e-12);
      if (massType == MassType::lumped) {
        EXPECT_LE(mode.fastShare, 1.0 + 1e-12);
      }
      EXPECT_DOUBLE_EQ(mode.fastShare, mode.regionShare[0]);
      sum += mode.fastShare;
    }
    const std::vector<int> regionDofs = freeDofsOf(system.freeDofs, region);
    double expected = static_cast<double>(regionDofs.size());
    if (massType == MassType::consistent) {
      const std::vector<int>& free = system.freeDofs.freeToFull();
      const Eigen::MatrixXd massFree =
          Eigen::MatrixXd(SubmatrixExtractor(system.mass, free, free).extract(system.mass));
      const Eigen::MatrixXd inverse = massFree.inverse();
      const std::vector<int>& toFree = system.freeDofs.fullToFree();
      expected = 0.0;
      for (int a : regionDofs)
        for (int b : regionDofs) expected += massFree(toFree[a], toFree[b]) * inverse(toFree[b], toFree[a]);
    }
    // The dense modes are M-orthonormal to about 1e-13; 108 of them add that up.
    EXPECT_NEAR(sum, expected, 1e-9 * expected);
  }
}

TEST(RegionModes, RegionSharesAddUpAndTimestepsFollowRatios) {
  const TetMesh mesh = tinyBox();
  const auto system = modalSystem(mesh, mesh.vertexSet("xmin"), MassType::consistent);
  const ModalResult modes = testing::lowestModesOf(system, 6);
  // Two regions sharing no element: the x = 1.5 face and the y = 0 face's x = 0 edge are
  // two cells apart, so M^{S1 S2} = 0.
  const std::vector<int> end = mesh.vertexSet("xmax");
  std::vector<int> corner;
  for (int v : mesh.vertexSet("ymin"))
    if (mesh.restPositions()(0, v) < 0.6) corner.push_back(v);
  std::vector<int> both = end;
  both.insert(both.end(), corner.begin(), corner.end());
  const RegionModeReport two =
      analyseRegionModes(modes, system.mass, {{"end", end, 4}, {"corner", corner, 2}}, 0.02, 60.0);
  const RegionModeReport one = analyseRegionModes(modes, system.mass, {{"both", both, 1}}, 0.02, 60.0);
  for (std::size_t j = 0; j < two.modes.size(); ++j) {
    EXPECT_NEAR(two.modes[j].fastShare, one.modes[j].fastShare, 1e-12);
    EXPECT_DOUBLE_EQ(two.modes[j].omegaLargeStep, modes.frequencies[static_cast<Eigen::Index>(j)] * 0.02);
    EXPECT_DOUBLE_EQ(two.modes[j].omegaSubstep[0], two.modes[j].omegaLargeStep / 4);
    EXPECT_DOUBLE_EQ(two.modes[j].omegaSubstep[1], two.modes[j].omegaLargeStep / 2);
  }
  EXPECT_DOUBLE_EQ(two.nyquistOmega, modalCriteria::nyquistPerFrameRate * 60.0);
}

// A stiff, heavy body with a light, very soft tip: the tip's own bending modes lie below
// the frame Nyquist frequency, carry nearly all their modal mass in the tip, are damped at
// hL = 1/120 (omega hL >= 0.5) and resolved at hS = hL / 8.
TEST(RegionModes, AsyncKeepsTheModesOfALightSoftTip) {
  BeamSpec spec;
  spec.cellsAlongLength = 10;
  spec.body = Material{"body", 1000.0, 1e9, 0.3};
  spec.tip = Material{"tip", 10.0, 3e3, 0.3};
  std::string table;
  const RegionModeReport report = tipReport(makeBeamMesh(spec), 6, table);
  ASSERT_EQ(report.verdict, ModalVerdict::asyncKeepsModes) << table;
  EXPECT_EQ(report.verdictText().rfind("async can keep these modes: 1 (", 0), 0u) << table;
  for (int j : report.keptModes) {
    const ModeInRegions& mode = report.modes[static_cast<std::size_t>(j)];
    EXPECT_GE(mode.fastShare, modalCriteria::minFastShare);
    EXPECT_LT(mode.omega, report.nyquistOmega);
  }
  EXPECT_NE(table.find("async can keep these modes"), std::string::npos);
}

// The default beam (models/beam/beam.veg, tip region, 30 frames/s, hL = 1/120, m = 8): the
// design note's counter-example. Every visible mode is a bending mode of the whole beam.
TEST(RegionModes, DefaultBeamHasNoVisibleModeInItsTip) {
  std::string table;
  const RegionModeReport report =
      tipReport(readMesh(std::filesystem::path(ASYNCFEM_MODELS_DIR) / "beam" / "beam.veg"), 12, table);
  EXPECT_EQ(report.verdict, ModalVerdict::noVisibleModeInFast) << table;
  EXPECT_FALSE(report.visibleModesTruncated) << table;
  for (const ModeInRegions& mode : report.modes) {
    if (mode.visible) {
      EXPECT_LE(mode.fastShare, 0.26) << table;
    }
  }
  EXPECT_NE(table.find("no mode below the frame Nyquist frequency lives in S: single-rate at hL costs less for "
                       "the same result"),
            std::string::npos);
}

TEST(RegionModes, VerdictsForModesResolvedAtHLOrUnresolvedAtHS) {
  // One hand-made mode on a single free vertex with unit lumped mass, fully in S.
  Eigen::SparseMatrix<double> mass(3, 3);
  mass.setIdentity();
  ModalResult result;
  result.modes = Eigen::MatrixXd::Zero(3, 1);
  result.modes(0, 0) = 1.0;
  result.frequencies = Eigen::VectorXd::Constant(1, 40.0);
  result.eigenvalues = result.frequencies.cwiseAbs2();
  const std::vector<ModalRegion> regions{{"s", {0}, 4}};
  EXPECT_EQ(analyseRegionModes(result, mass, regions, 0.005, 30.0).verdict, ModalVerdict::resolvedAtLargeStep);
  EXPECT_EQ(analyseRegionModes(result, mass, regions, 0.02, 30.0).verdict, ModalVerdict::unresolvedAtSubstep);
  EXPECT_EQ(analyseRegionModes(result, mass, {{"s", {0}, 8}}, 0.02, 30.0).verdict, ModalVerdict::asyncKeepsModes);
  EXPECT_EQ(analyseRegionModes(result, mass, {}, 0.02, 30.0).verdict, ModalVerdict::noVisibleModeInFast);
  EXPECT_EQ(analyseRegionModes(result, mass, regions, 0.02, 10.0).verdict, ModalVerdict::noVisibleModeInFast);
}

TEST(RegionModes, RejectsBadArguments) {
  Eigen::SparseMatrix<double> mass(3, 3);
  mass.setIdentity();
  ModalResult result;
  result.modes = Eigen::MatrixXd::Identity(3, 1);
  result.frequencies = Eigen::VectorXd::Ones(1);
  const auto expectError = [&](const std::vector<ModalRegion>& regions, double hL, double rate,
                               const std::string& expected) {
    try {
      analyseRegionModes(result, mass, regions, hL, rate);
      ADD_FAILURE() << "no error for " << expected;
    } catch (const ValidationError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  expectError({}, 0.0, 30.0, "large timestep hL must be positive");
  expectError({}, 0.01, -1.0, "frame rate must be positive");
  expectError({{"s", {0}, 0}}, 0.01, 30.0, "region 's' has ratio 0");
  expectError({{"s", {1}, 2}}, 0.01, 30.0, "names vertex 1, outside [0, 1)");
  Eigen::SparseMatrix<double> bigger(6, 6);
  bigger.setIdentity();
  EXPECT_THROW(analyseRegionModes(result, bigger, {}, 0.01, 30.0), ValidationError);
}

}  // namespace
}  // namespace asyncfem
