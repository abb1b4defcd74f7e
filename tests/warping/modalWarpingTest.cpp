// SPDX-License-Identifier: BSD-3-Clause
// ModalWarping: rest shape, translations, large linearised rotations, the curl operator.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/warping/modalWarping.hpp>
#include <cmath>
#include <numbers>

#include "warpingTestHelpers.hpp"

namespace {

using asyncfem::ModalWarping;
using namespace asyncfem::testing;

constexpr double degree = std::numbers::pi / 180.0;

TEST(ModalWarping, ZeroDisplacementGivesTheRestShapeExactly) {
  const asyncfem::TetMesh mesh = warpingTestBox();
  ModalWarping warping(mesh);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(mesh.numDofs());
  EXPECT_EQ(warping.warp(zero), zero);
}

TEST(ModalWarping, TranslationStaysTheTranslation) {
  const asyncfem::TetMesh mesh = warpingTestBox();
  ModalWarping warping(mesh);
  const Eigen::Vector3d t(-0.4, 1.1, 0.9);
  const Eigen::VectorXd u = sampleField(mesh, [&](const Eigen::Vector3d&) -> Eigen::Vector3d { return t; });
  // The curl of a constant field cancels to rounding, so w ~ 1e-16 and u~ = u + O(w |u|).
  EXPECT_LE((warping.warp(u) - u).cwiseAbs().maxCoeff(), 1e-12 * t.norm());
}

TEST(ModalWarping, CurlOfALinearizedRotationIsTheRotationVector) {
  const asyncfem::TetMesh mesh = warpingTestBox();
  ModalWarping warping(mesh);
  const Eigen::Vector3d axis = Eigen::Vector3d(-1.0, 0.5, 2.0).normalized();
  const double theta = 0.8;
  const Eigen::VectorXd w = warping.rotationVectors(linearizedRotation(mesh, theta, axis, Eigen::Vector3d::Ones()));
  for (int v = 0; v < mesh.numVertices(); ++v) {
    EXPECT_LE((w.segment<3>(3 * v) - theta * axis).norm(), 1e-12) << "vertex " << v;
  }
}

TEST(ModalWarping, LinearizedLargeRotationBecomesRigid) {
  const asyncfem::TetMesh mesh = warpingTestBox();
  ModalWarping warping(mesh);
  for (const double angle : {60.0, 75.0, 90.0}) {
    const Eigen::Vector3d axis(2.0, -1.0, 0.5);
    const Eigen::Vector3d center(1.3, 0.3, 0.6);
    const Eigen::VectorXd linear = linearizedRotation(mesh, angle * degree, axis, center);
    const Eigen::VectorXd warped = warping.warp(linear);
    const double rawError = maxEdgeLengthError(mesh, linear);
    EXPECT_GT(rawError, 0.2) << angle << " degrees";
    // int_0^theta R(phi a) [a]x dphi = R - I exactly; only rounding of w (1e-15) is left.
    EXPECT_LE(maxEdgeLengthError(mesh, warped), 1e-12) << angle << " degrees";
    // It is the exact rotation about the same center.
    const Eigen::VectorXd exact = rigidRotation(mesh, angle * degree, axis, center);
    EXPECT_LE((warped - exact).cwiseAbs().maxCoeff(), 1e-12) << angle << " degrees";
  }
}

TEST(ModalWarping, FixedVerticesStayFixed) {
  const asyncfem::TetMesh mesh = warpingTestBox();
  ModalWarping warping(mesh);
  Eigen::VectorXd u = linearizedRotation(mesh, 1.2, Eigen::Vector3d::UnitZ(), Eigen::Vector3d(0.3, 0.3, 0.6));
  for (const int v : mesh.vertexSet("xmin")) {
    u.segment<3>(3 * v).setZero();
  }
  const Eigen::VectorXd warped = warping.warp(u);
  for (const int v : mesh.vertexSet("xmin")) {
    EXPECT_EQ(warped.segment<3>(3 * v), Eigen::Vector3d::Zero());
  }
}

TEST(ModalWarping, WrongSizeIsAnError) {
  const asyncfem::TetMesh mesh = warpingTestBox();
  ModalWarping warping(mesh);
  EXPECT_THROW(warping.warp(Eigen::VectorXd::Zero(7)), asyncfem::Error);
}

}  // namespace
