// SPDX-License-Identifier: BSD-3-Clause
// RotationStrainWarping: rest shape, translations, large linearised rotations, fixed
// vertices, several components, errors.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/warping/rotationStrainWarping.hpp>
#include <cmath>
#include <numbers>

#include "warpingTestHelpers.hpp"

namespace {

using asyncfem::RotationStrainWarping;
using namespace asyncfem::testing;

constexpr double degree = std::numbers::pi / 180.0;

TEST(RotationStrainWarping, ZeroDisplacementGivesTheRestShapeExactly) {
  const asyncfem::TetMesh mesh = warpingTestBox();
  RotationStrainWarping warping(mesh);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(mesh.numDofs());
  const Eigen::VectorXd warped = warping.warp(zero);
  // R = I, S = 0 and b = 0 exactly, and a zero right-hand side solves to exactly zero.
  EXPECT_EQ(warped, zero);
}

TEST(RotationStrainWarping, TranslationStaysTheTranslation) {
  const asyncfem::TetMesh mesh = warpingTestBox();
  RotationStrainWarping warping(mesh);
  const Eigen::Vector3d t(0.7, -1.3, 2.1);
  const Eigen::VectorXd u = sampleField(mesh, [&](const Eigen::Vector3d&) -> Eigen::Vector3d { return t; });
  const Eigen::VectorXd warped = warping.warp(u);
  // The gradient of a constant field is a sum of shape gradients that cancels to
  // rounding (~1e-16 / cell size); the solve and the mean shift add a few ulps of |t|.
  EXPECT_LE((warped - u).cwiseAbs().maxCoeff(), 1e-12 * t.norm());
}

TEST(RotationStrainWarping, LinearizedLargeRotationBecomesRigid) {
  const asyncfem::TetMesh mesh = warpingTestBox();
  RotationStrainWarping warping(mesh);
  for (const double angle : {60.0, 75.0, 90.0}) {
    const Eigen::Vector3d axis(1.0, 2.0, 3.0);
    const Eigen::Vector3d center(1.0, 0.5, -0.5);
    const Eigen::VectorXd linear = linearizedRotation(mesh, angle * degree, axis, center);
    const Eigen::VectorXd warped = warping.warp(linear);

    // The raw linear result stretches by sqrt(1 + theta^2) across the axis (25% at 60
    // degrees for edges perpendicular to it; the box has such edges within a few degrees).
    const double rawError = maxEdgeLengthError(mesh, linear);
    EXPECT_GT(rawError, 0.2) << angle << " degrees";
    // Warped: F_e = exp(theta [a]x) is the same rotation in every element, so the
    // least-squares positions are that rotation exactly; what is left is rounding of the
    // solve (condition number of L ~ 1e2 here), bounded by 1e-10.
    const double warpedError = maxEdgeLengthError(mesh, warped);
    EXPECT_LE(warpedError, 1e-10) << angle << " degrees";
    EXPECT_LT(warpedError, 1e-6 * rawError);

    // And it is the rotation by theta itself: every edge is turned by R.
    const Eigen::Matrix3d r = Eigen::AngleAxisd(angle * degree, axis.normalized()).toRotationMatrix();
    const Eigen::Vector3d e0 = mesh.restPosition(1) - mesh.restPosition(0);
    const Eigen::Vector3d warpedE0 = e0 + warped.segment<3>(3) - warped.segment<3>(0);
    EXPECT_LE((warpedE0 - r * e0).norm(), 1e-10 * e0.norm());
    // No fixed vertex: the centroid stays where the linear result puts it.
    EXPECT_LE((meanPosition(mesh, warped) - meanPosition(mesh, linear)).norm(), 1e-12);
  }
}

TEST(RotationStrainWarping, FixedVerticesKeepTheirDisplacement) {
  const asyncfem::TetMesh mesh = warpingTestBox();
  const std::vector<int>& fixed = mesh.vertexSet("xmin");
  RotationStrainWarping warping(mesh, fixed);
  EXPECT_EQ(warping.numComponents(), 1);
  EXPECT_EQ(warping.numUnknowns(), mesh.numVertices() - static_cast<int>(fixed.size()));
  EXPECT_EQ(warping.warp(Eigen::VectorXd::Zero(mesh.numDofs())), Eigen::VectorXd::Zero(mesh.numDofs()));

  // A cantilever in linear (Euler-Bernoulli) bending about z, zero on its fixed face
  // x = x0: u_x = -k (x - x0)(y - yc), u_y = k (x - x0)^2 / 2, with k L = 1.2 rad of tip
  // rotation. Fixed vertices keep zero; the rest loses most of the linear growth.
  const double x0 = 0.3;
  const double yc = 0.3;
  const double curvature = 0.6;
  const Eigen::VectorXd u = sampleField(mesh, [&](const Eigen::Vector3d& x) -> Eigen::Vector3d {
    return {-curvature * (x.x() - x0) * (x.y() - yc), 0.5 * curvature * (x.x() - x0) * (x.x() - x0), 0.0};
  });
  const Eigen::VectorXd warped = warping.warp(u);
  for (const int v : fixed) {
    EXPECT_EQ(warped.segment<3>(3 * v), Eigen::Vector3d::Zero()) << "vertex " << v;
  }
  // The neutral axis (y = yc) is unstrained in bending, so the length change of its edges
  // is pure linearization error: sqrt(1 + theta^2) - 1 with theta the local rotation, 45%
  // for the last edge (mean theta 1.05) raw.
  const auto neutralAxisError = [&](const Eigen::VectorXd& displacement) {
    double worst = 0.0;
    for (int i = 0; i < mesh.numVertices(); ++i) {
      for (int j = 0; j < mesh.numVertices(); ++j) {
        const Eigen::Vector3d restEdge = mesh.restPosition(j) - mesh.restPosition(i);
        if (std::abs(mesh.restPosition(i).y() - yc) > 1e-12 || std::abs(restEdge.x() - 0.5) > 1e-12 ||
            restEdge.tail<2>().norm() > 1e-12) {
          continue;
        }
        const Eigen::Vector3d edge = restEdge + displacement.segment<3>(3 * j) - displacement.segment<3>(3 * i);
        worst = std::max(worst, std::abs(edge.norm() - restEdge.norm()) / restEdge.norm());
      }
    }
    return worst;
  };
  const double rawAxisError = neutralAxisError(u);
  EXPECT_GT(rawAxisError, 0.4);
  // Warped: the element rotations follow the bending, leaving the small coupling error of
  // the least-squares fit (0.3% on this coarse mesh).
  EXPECT_LT(neutralAxisError(warped), 0.1 * rawAxisError);
  EXPECT_LT(maxEdgeLengthError(mesh, warped), 0.5 * maxEdgeLengthError(mesh, u));
}

TEST(RotationStrainWarping, EveryComponentIsWarpedOnItsOwn) {
  // Two boxes side by side sharing no vertex: each component is pinned and re-centred
  // separately, so each keeps its own centroid under its own linearised rotation.
  const asyncfem::TetMesh a = warpingTestBox();
  const int n = a.numVertices();
  Eigen::Matrix3Xd positions(3, 2 * n);
  positions << a.restPositions(), a.restPositions().colwise() + Eigen::Vector3d(5.0, 0.0, 0.0);
  Eigen::Matrix4Xi elements(4, 2 * a.numElements());
  elements << a.elements(), a.elements().array() + n;
  std::vector<int> materials(static_cast<std::size_t>(2 * a.numElements()), 0);
  const asyncfem::TetMesh mesh(positions, elements, a.materials(), materials);
  RotationStrainWarping warping(mesh);
  EXPECT_EQ(warping.numComponents(), 2);

  Eigen::VectorXd u(mesh.numDofs());
  u.head(3 * n) = linearizedRotation(a, 80.0 * degree, Eigen::Vector3d::UnitX(), Eigen::Vector3d::Zero());
  u.tail(3 * n) = Eigen::VectorXd::Constant(3 * n, 0.25);
  const Eigen::VectorXd warped = warping.warp(u);
  EXPECT_LE(maxEdgeLengthError(mesh, warped), 1e-10);
  EXPECT_LE((warped.tail(3 * n) - u.tail(3 * n)).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(RotationStrainWarping, ExactRotationFieldIsNotRigidButStaysClose) {
  // u = (R - I) X is already rigid; its gradient R - I has skew part sin(theta) [a]x, so
  // the method (built for linearised fields) turns it by asin-like angles instead. This
  // documents the limit: apply warping to linear FEM output, not to corotated output.
  const asyncfem::TetMesh mesh = warpingTestBox();
  RotationStrainWarping warping(mesh);
  const Eigen::VectorXd exact = rigidRotation(mesh, 60.0 * degree, Eigen::Vector3d::UnitZ(), Eigen::Vector3d::Zero());
  EXPECT_LE(maxEdgeLengthError(mesh, exact), 1e-12);
  EXPECT_GT(maxEdgeLengthError(mesh, warping.warp(exact)), 1e-3);
}

TEST(RotationStrainWarping, ErrorsNameTheProblem) {
  const asyncfem::TetMesh mesh = warpingTestBox();
  try {
    RotationStrainWarping warping(mesh, {0, mesh.numVertices()});
    FAIL() << "expected ValidationError";
  } catch (const asyncfem::ValidationError& e) {
    EXPECT_NE(std::string(e.what()).find("fixed vertex " + std::to_string(mesh.numVertices())), std::string::npos)
        << e.what();
  }
  RotationStrainWarping warping(mesh);
  try {
    warping.warp(Eigen::VectorXd::Zero(5));
    FAIL() << "expected Error";
  } catch (const asyncfem::Error& e) {
    EXPECT_NE(std::string(e.what()).find("5 entries"), std::string::npos) << e.what();
  }
}

}  // namespace
