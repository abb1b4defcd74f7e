// SPDX-License-Identifier: BSD-3-Clause
// fitCamera and projectToPixel.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/render/camera.hpp>

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
      const Eigen::Vector3d c((corner & 1) != 0 ? box.max.x() : box.min.x(),
                              (corner & 2) != 0 ? box.max.y() : box.min.y(),
                              (corner & 4) != 0 ? box.max.z() : box.min.z());
      const Eigen::Vector2d p = projectToPixel(camera, width, height, c);
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

}  // namespace
