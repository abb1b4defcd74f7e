// SPDX-License-Identifier: BSD-3-Clause
// fitCamera, projectToPixel and groundBelow.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/render/camera.hpp>
#include <asyncfem/render/renderer.hpp>

namespace {

using namespace asyncfem;

TEST(Camera, TargetProjectsToTheImageCentre) {
  Camera camera;
  camera.position = Eigen::Vector3d(1.0, 2.0, 3.0);
  camera.target = Eigen::Vector3d(-0.5, 0.2, 0.1);
  const Eigen::Vector2d p = projectToPixel(camera, 200, 100, camera.target);
  EXPECT_NEAR(p.x(), 100.0, 1e-9);
  EXPECT_NEAR(p.y(), 50.0, 1e-9);
  // Up in the world is up in the image (smaller y), right is right.
  Camera front;
  EXPECT_LT(projectToPixel(front, 100, 100, Eigen::Vector3d(0.0, 0.5, 0.0)).y(), 50.0);
  EXPECT_GT(projectToPixel(front, 100, 100, Eigen::Vector3d(0.5, 0.0, 0.0)).x(), 50.0);
}

TEST(Camera, FittedCameraShowsEveryCornerWithTheMargin) {
  const BoundingBox box{Eigen::Vector3d(-1.0, 0.2, 0.0), Eigen::Vector3d(3.0, 0.9, 0.5)};
  for (const double aspect : {0.5, 1.0, 16.0 / 9.0}) {
    const int height = 360;  // integer widths for these aspects
    const int width = static_cast<int>(height * aspect);
    const Camera camera = fitCamera(box, aspect);
    double worst = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector2d p = projectToPixel(camera, width, height, boxCorner(box, corner));
      // Normalised distance from the centre: 1 at the border, 0.92 at the margin.
      const double u = std::abs(p.x() - (0.5 * width)) / (0.5 * width);
      const double v = std::abs(p.y() - (0.5 * height)) / (0.5 * height);
      EXPECT_LE(u, 0.92 + 1e-9);
      EXPECT_LE(v, 0.92 + 1e-9);
      worst = std::max({worst, u, v});
    }
    EXPECT_NEAR(worst, 0.92, 1e-9) << "aspect " << aspect;  // tight: some corner on the margin
  }
  EXPECT_THROW(fitCamera(box, 1.0, Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitY()), Error);
}

// groundAt puts the floor at a given height along up (a scene's contact.ground), centred
// under the box and sized like groundBelow's (1e-12: round-off of the projections).
TEST(GroundPlane, GroundAtIsAtTheGivenHeightUnderTheBox) {
  const BoundingBox box{Eigen::Vector3d(0.0, 1.0, 0.0), Eigen::Vector3d(2.0, 3.0, 4.0)};
  const GroundPlane at = groundAt(box, Eigen::Vector3d(0.0, 3.0, 0.0), -0.5);
  EXPECT_NEAR((at.center - Eigen::Vector3d(1.0, -0.5, 2.0)).norm(), 0.0, 1e-12);
  const GroundPlane below = groundBelow(box, Eigen::Vector3d::UnitY());
  EXPECT_EQ(at.halfSize, below.halfSize);
  EXPECT_EQ(at.tileSize, below.tileSize);
  EXPECT_LT(below.center.y(), 1.0);  // groundBelow: under the box, not at a given height
}

TEST(GroundPlane, LiesJustBelowTheLowestCornerAlongUp) {
  // Diagonal 3 (sides 1, 2, 2): the plane sits 0.06 below the lowest corner, tiles near
  // 3/6 = 0.5 round to 0.5, and the plane reaches 4 diagonals to each side.
  const BoundingBox box{Eigen::Vector3d(-1.0, 0.5, 0.0), Eigen::Vector3d(0.0, 2.5, 2.0)};
  const GroundPlane yUp = groundBelow(box, Eigen::Vector3d(0.0, 2.0, 0.0));
  EXPECT_NEAR(yUp.center.y(), 0.5 - 0.06, 1e-12);
  EXPECT_NEAR(yUp.center.x(), -0.5, 1e-12);
  EXPECT_NEAR(yUp.center.z(), 1.0, 1e-12);
  EXPECT_NEAR(yUp.halfSize, 12.0, 1e-12);
  EXPECT_NEAR(yUp.tileSize, 0.5, 1e-12);
  EXPECT_TRUE(yUp.shadow);
  // Up along -z: the lowest corner is the one with the largest z.
  const GroundPlane zDown = groundBelow(box, Eigen::Vector3d(0.0, 0.0, -1.0));
  EXPECT_NEAR(zDown.center.z(), 2.0 + 0.06, 1e-12);
  // Tile sizes are 1, 2 or 5 times a power of ten.
  const BoundingBox small{Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 0.0, 0.09)};
  EXPECT_NEAR(groundBelow(small, Eigen::Vector3d::UnitY()).tileSize, 0.02, 1e-15);  // 0.09 / 6 = 0.015
}

}  // namespace
