// SPDX-License-Identifier: BSD-3-Clause
// Modal and rotation-strain warping on trilinear hexahedra: rotations from each element's
// centre gradient, vertex weights by element volume (modal), Gauss-point Laplacian
// (rotation-strain).
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <asyncfem/warping/modalWarping.hpp>
#include <asyncfem/warping/rotationStrainWarping.hpp>
#include <asyncfem/warping/warping.hpp>
#include <numbers>

#include "warpingTestHelpers.hpp"

namespace {

using namespace asyncfem;
using namespace asyncfem::testing;

constexpr double degree = std::numbers::pi / 180.0;

// Both bars: cubes, and general hexahedra (interior vertices moved by up to 0.01 of the
// 0.125 spacing). Trilinear interpolation reproduces every affine field, so the centre
// gradient of a linearised rotation is exactly theta [a]x on both.
constexpr double kWobbles[] = {0.0, 0.01};

TEST(HexahedralWarping, ModalCurlOfALinearizedRotationIsTheRotationVector) {
  for (const double wobble : kWobbles) {
    const TetMesh mesh = warpingTestHexBar(wobble);
    ASSERT_TRUE(mesh.isHexahedral());
    ModalWarping warping(mesh);
    const Eigen::Vector3d axis = Eigen::Vector3d(-1.0, 0.5, 2.0).normalized();
    const Eigen::VectorXd w = warping.rotationVectors(linearizedRotation(mesh, 0.8, axis, Eigen::Vector3d::Ones()));
    for (int v = 0; v < mesh.numVertices(); ++v) {
      // Rounding of the gradients (condition of J ~ 1) and of the volume-weighted mean.
      EXPECT_LE((w.segment<3>(3 * v) - 0.8 * axis).norm(), 1e-12) << "wobble " << wobble << ", vertex " << v;
    }
  }
}

TEST(HexahedralWarping, LinearizedLargeRotationBecomesRigid) {
  for (const double wobble : kWobbles) {
    const TetMesh mesh = warpingTestHexBar(wobble);
    ModalWarping modal(mesh);
    RotationStrainWarping rotationStrain(mesh);
    for (const double angle : {60.0, 90.0}) {
      const Eigen::Vector3d axis(2.0, -1.0, 0.5);
      const Eigen::Vector3d center(0.6, 0.3, 0.1);
      const Eigen::VectorXd linear = linearizedRotation(mesh, angle * degree, axis, center);
      EXPECT_GT(maxEdgeLengthError(mesh, linear), 0.2) << angle << " degrees";
      const Eigen::VectorXd exact = rigidRotation(mesh, angle * degree, axis, center);
      // Modal: exact up to rounding of w (as on tetrahedra).
      EXPECT_LE((modal.warp(linear) - exact).cwiseAbs().maxCoeff(), 1e-12) << "wobble " << wobble;
      // Rotation-strain: F_e = R in every element, so w = (R - I) X solves the least-squares
      // problem exactly; rounding of the solve (condition of L ~ 1e2) is left, below 1e-10.
      // The mean displacement is the linear one's, which for a rigid motion about `center`
      // differs from the exact rotation's by a translation: compare edge lengths and shapes.
      const Eigen::VectorXd warped = rotationStrain.warp(linear);
      EXPECT_LE(maxEdgeLengthError(mesh, warped), 1e-10) << "wobble " << wobble << ", " << angle << " degrees";
      const Eigen::Vector3d shift = meanPosition(mesh, warped) - meanPosition(mesh, exact);
      for (int v = 0; v < mesh.numVertices(); ++v) {
        EXPECT_LE((warped.segment<3>(3 * v) - exact.segment<3>(3 * v) - shift).norm(), 1e-10) << "vertex " << v;
      }
    }
  }
}

TEST(HexahedralWarping, FixedVerticesAndTheRestShapeStay) {
  const TetMesh mesh = warpingTestHexBar(0.01);
  std::vector<int> root;
  for (int v = 0; v < mesh.numVertices(); ++v)
    if (mesh.restPosition(v).x() == 0.0) root.push_back(v);
  ASSERT_EQ(root.size(), 9U);
  for (const WarpingKind kind : {WarpingKind::modal, WarpingKind::rotationStrain}) {
    const std::unique_ptr<Warping> warping = makeWarping(kind, mesh, root);
    EXPECT_EQ(warping->warp(Eigen::VectorXd::Zero(mesh.numDofs())), Eigen::VectorXd::Zero(mesh.numDofs()));
    Eigen::VectorXd u = linearizedRotation(mesh, 1.2, Eigen::Vector3d::UnitZ(), Eigen::Vector3d(0.0, 0.1, 0.1));
    for (const int v : root) u.segment<3>(3 * v).setZero();
    const Eigen::VectorXd warped = warping->warp(u);
    for (const int v : root) EXPECT_EQ(warped.segment<3>(3 * v), Eigen::Vector3d::Zero()) << toString(kind);
    EXPECT_TRUE(warped.allFinite()) << toString(kind);
  }
}

TEST(HexahedralWarping, ADegenerateHexahedronIsNamed) {
  // Element 1 of two: its top face lies on its bottom face (vertices 8 .. 11 at z = 0).
  Eigen::Matrix3Xd x(3, 12);
  x << 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1, 0,  //
      0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1,   //
      0, 0, 0, 0, 1, 1, 1, 1, 0, 0, 0, 0;
  HexElements cubes(8, 2);
  cubes.col(0) << 0, 1, 2, 3, 4, 5, 6, 7;
  cubes.col(1) << 0, 1, 2, 3, 8, 9, 10, 11;
  const TetMesh flat(x, cubes, {Material{"m", 1000.0, 1e6, 0.3}}, {0, 0});
  for (const WarpingKind kind : {WarpingKind::modal, WarpingKind::rotationStrain}) {
    try {
      makeWarping(kind, flat);
      FAIL() << "expected ValidationError";
    } catch (const ValidationError& e) {
      EXPECT_NE(std::string(e.what()).find("warping: element 1 is degenerate"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
