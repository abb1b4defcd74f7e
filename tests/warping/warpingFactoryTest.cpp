// SPDX-License-Identifier: BSD-3-Clause
// WarpingKind names, makeWarping and deformedPositions.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/warping/warping.hpp>

#include "warpingTestHelpers.hpp"

namespace {

TEST(WarpingFactory, NamesRoundTrip) {
  for (const auto kind :
       {asyncfem::WarpingKind::none, asyncfem::WarpingKind::rotationStrain, asyncfem::WarpingKind::modal}) {
    EXPECT_EQ(asyncfem::parseWarpingKind(asyncfem::toString(kind)), kind);
  }
  try {
    asyncfem::parseWarpingKind("rotation");
    FAIL() << "expected Error";
  } catch (const asyncfem::Error& e) {
    EXPECT_NE(std::string(e.what()).find("\"rotation\""), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("rotation-strain"), std::string::npos);
  }
}

TEST(WarpingFactory, MakesEveryKind) {
  const asyncfem::TetMesh mesh = asyncfem::testing::warpingTestBox();
  const Eigen::VectorXd u = Eigen::VectorXd::LinSpaced(mesh.numDofs(), 0.0, 0.01);
  for (const auto kind :
       {asyncfem::WarpingKind::none, asyncfem::WarpingKind::rotationStrain, asyncfem::WarpingKind::modal}) {
    const auto warping = asyncfem::makeWarping(kind, mesh);
    EXPECT_EQ(warping->kind(), kind);
    EXPECT_EQ(warping->numVertices(), mesh.numVertices());
    EXPECT_EQ(warping->warp(u).size(), u.size());
  }
  EXPECT_EQ(asyncfem::makeWarping(asyncfem::WarpingKind::none, mesh)->warp(u), u);
}

TEST(WarpingFactory, DeformedPositionsAddTheDisplacement) {
  const asyncfem::TetMesh mesh = asyncfem::testing::warpingTestBox();
  const Eigen::VectorXd u = Eigen::VectorXd::LinSpaced(mesh.numDofs(), -1.0, 1.0);
  const Eigen::Matrix3Xd x = asyncfem::deformedPositions(mesh, u);
  EXPECT_EQ(x.col(3), mesh.restPosition(3) + u.segment<3>(9));
  EXPECT_THROW(asyncfem::deformedPositions(mesh, Eigen::VectorXd::Zero(2)), asyncfem::Error);
}

}  // namespace
