// SPDX-License-Identifier: BSD-3-Clause
// OffscreenRenderer: image size, where the object lands, tints, determinism, errors.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/render/renderer.hpp>
#include <asyncfem/render/surfaceEmbedding.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>

#include "renderTestHelpers.hpp"

namespace {

using namespace asyncfem;
using namespace asyncfem::renderTesting;

struct BarFrame {
  TetMesh mesh = renderTestBar();
  SurfaceEmbedding surface = SurfaceEmbedding::boundary(mesh);
  Eigen::VectorXd displacement = bentBar(mesh);
  Eigen::Matrix3Xd positions = surface.positions(displacement);
};

TEST(OffscreenRenderer, ImageHasTheRequestedSize) {
  const BarFrame bar;
  for (const auto& [width, height] : {std::pair{160, 90}, std::pair{33, 71}}) {
    OffscreenRenderer renderer(width, height);
    const Camera camera = fitCamera(boundingBox(bar.mesh, bar.displacement), static_cast<double>(width) / height);
    const Image image = renderer.render({{bar.positions, bar.surface.triangles()}}, camera, RenderStyle{});
    EXPECT_EQ(image.width, width);
    EXPECT_EQ(image.height, height);
    EXPECT_EQ(image.pixels.size(), 3U * width * height);
  }
}

TEST(OffscreenRenderer, ObjectPixelsLieInsideTheProjectedBoundingBox) {
  const BarFrame bar;
  const int width = 200;
  const int height = 120;
  const BoundingBox box = boundingBox(bar.mesh, bar.displacement);
  // A camera that does not centre the box, so a wrong projection would show.
  Camera camera = fitCamera(box, static_cast<double>(width) / height, Eigen::Vector3d(-0.3, 0.6, 1.0));
  camera.target += Eigen::Vector3d(0.2, 0.1, 0.0);
  OffscreenRenderer renderer(width, height, 1);
  RenderStyle style;
  style.background = Eigen::Vector3f(0.0F, 0.0F, 0.0F);
  const Image image = renderer.render({{bar.positions, bar.surface.triangles()}}, camera, style);

  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e300);
  Eigen::Vector2d hi = -lo;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d p((corner & 1) != 0 ? box.max.x() : box.min.x(),
                            (corner & 2) != 0 ? box.max.y() : box.min.y(),
                            (corner & 4) != 0 ? box.max.z() : box.min.z());
    const Eigen::Vector2d q = projectToPixel(camera, width, height, p);
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  int objectPixels = 0;
  Eigen::Vector2i objectLo(width, height);
  Eigen::Vector2i objectHi(-1, -1);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      if (!differsFrom(image, x, y, Eigen::Vector3i::Zero())) {
        continue;
      }
      ++objectPixels;
      objectLo = objectLo.cwiseMin(Eigen::Vector2i(x, y));
      objectHi = objectHi.cwiseMax(Eigen::Vector2i(x, y));
      // A covered pixel [x, x+1) x [y, y+1) must overlap the projected box.
      EXPECT_GE(x + 1, lo.x()) << x << ", " << y;
      EXPECT_LE(x, hi.x()) << x << ", " << y;
      EXPECT_GE(y + 1, lo.y()) << x << ", " << y;
      EXPECT_LE(y, hi.y()) << x << ", " << y;
    }
  }
  EXPECT_GT(objectPixels, 500);
  // And the object spans most of its box's projection (not a sliver in one corner).
  EXPECT_GE(objectHi.x() - objectLo.x(), 0.6 * (hi.x() - lo.x()));
}

TEST(OffscreenRenderer, FittedCameraCentresAndFramesTheObject) {
  const BarFrame bar;
  const int width = 160;
  const int height = 100;
  const Camera camera = fitCamera(boundingBox(bar.mesh, bar.displacement), 1.6);
  OffscreenRenderer renderer(width, height);
  const Image image = renderer.render({{bar.positions, bar.surface.triangles()}}, camera, RenderStyle{});
  // Background is white; the object must not touch the border (8% margin) and must
  // span most of the width.
  int minX = width;
  int maxX = -1;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      if (differsFrom(image, x, y, Eigen::Vector3i::Constant(255), 2)) {
        minX = std::min(minX, x);
        maxX = std::max(maxX, x);
        EXPECT_TRUE(x > 0 && y > 0 && x < width - 1 && y < height - 1) << x << ", " << y;
      }
    }
  }
  EXPECT_GT(maxX - minX, width / 2);
  EXPECT_LE(std::abs((minX + maxX) / 2 - width / 2), width / 5);
}

/// Pixels whose colour reads as the orange tint (red well above blue) under any lighting.
int tintedPixels(const Image& image) {
  int count = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const std::uint8_t* p = image.pixel(x, y);
      if (p[0] > p[2] + 40 && p[0] > p[1] + 20) {
        ++count;
      }
    }
  }
  return count;
}

TEST(OffscreenRenderer, RegionTintIsPresentOnlyWhenTinted) {
  const BarFrame bar;
  const Camera camera = fitCamera(boundingBox(bar.mesh, bar.displacement), 1.5);
  OffscreenRenderer renderer(150, 100);
  const RenderStyle style;

  const Image plain = renderer.render({{bar.positions, bar.surface.triangles()}}, camera, style);
  EXPECT_EQ(tintedPixels(plain), 0);

  // Tint the tet vertices of the last fifth of the bar.
  Eigen::Matrix3Xf tetColors = style.surfaceColor.replicate(1, bar.mesh.numVertices());
  for (int v = 0; v < bar.mesh.numVertices(); ++v) {
    if (bar.mesh.restPosition(v).x() >= 1.6 - 1e-9) {
      tetColors.col(v) = Eigen::Vector3f(0.95F, 0.45F, 0.12F);
    }
  }
  const Eigen::Matrix3Xf colors = bar.surface.interpolate(tetColors);
  const Image tinted = renderer.render({{bar.positions, bar.surface.triangles(), &colors}}, camera, style);
  EXPECT_GT(tintedPixels(tinted), 200);
}

TEST(OffscreenRenderer, SameInputRendersTheSameImage) {
  const BarFrame bar;
  const Camera camera = fitCamera(boundingBox(bar.mesh, bar.displacement), 1.5);
  RenderStyle style;
  style.ground = GroundPlane{Eigen::Vector3d(1.0, -0.7, 0.2), 2.0, 0.25, true};
  OffscreenRenderer first(120, 80);
  OffscreenRenderer second(120, 80);
  const Image a = first.render({{bar.positions, bar.surface.triangles()}}, camera, style);
  // Something else in between, on the same context.
  first.render({{bar.surface.restSurface().vertices, bar.surface.triangles()}}, camera, RenderStyle{});
  const Image b = first.render({{bar.positions, bar.surface.triangles()}}, camera, style);
  const Image c = second.render({{bar.positions, bar.surface.triangles()}}, camera, style);
  EXPECT_TRUE(a == b);
  EXPECT_TRUE(a == c);
}

TEST(OffscreenRenderer, GroundPlaneShowsBelowTheObject) {
  const BarFrame bar;
  const BoundingBox box = boundingBox(bar.mesh, bar.displacement);
  const Camera camera = fitCamera(box, 1.5);
  RenderStyle style;
  style.background = Eigen::Vector3f(0.0F, 0.0F, 0.0F);
  style.ground = GroundPlane{Eigen::Vector3d(1.0, box.min.y() - 0.05, 0.2), 3.0, 0.3, true};
  OffscreenRenderer renderer(120, 80);
  const Image image = renderer.render({{bar.positions, bar.surface.triangles()}}, camera, style);
  // The bottom row looks at the floor: not the black background.
  int floorPixels = 0;
  for (int x = 0; x < image.width; ++x) {
    floorPixels += differsFrom(image, x, image.height - 1, Eigen::Vector3i::Zero(), 10) ? 1 : 0;
  }
  EXPECT_GT(floorPixels, image.width / 2);
}

TEST(OffscreenRenderer, BadInputIsAnError) {
  EXPECT_THROW(OffscreenRenderer(0, 10), Error);
  EXPECT_THROW(OffscreenRenderer(10, 10, 9), Error);
  OffscreenRenderer renderer(16, 16);
  const Eigen::Matrix3Xd positions = Eigen::Matrix3Xd::Random(3, 3);
  const std::vector<std::array<int, 3>> triangles{{0, 1, 3}};
  try {
    renderer.render({{positions, triangles}}, Camera{}, RenderStyle{});
    FAIL() << "expected Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 3"), std::string::npos) << e.what();
  }
  const std::vector<std::array<int, 3>> ok{{0, 1, 2}};
  const Eigen::Matrix3Xf colors = Eigen::Matrix3Xf::Ones(3, 2);
  EXPECT_THROW(renderer.render({{positions, ok, &colors}}, Camera{}, RenderStyle{}), Error);
}

}  // namespace
