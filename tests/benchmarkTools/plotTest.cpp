// SPDX-License-Identifier: BSD-3-Clause
// The plot rasterizer draws axes, markers and text where it should.
#include <gtest/gtest.h>

#include <asyncfem/benchmarkTools/plot.hpp>
#include <asyncfem/image/text.hpp>

namespace asyncfem {
namespace {

int countNonWhite(const Image& image) {
  int count = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const Rgb8 c = image.at(x, y);
      if (c.r != 255 || c.g != 255 || c.b != 255) ++count;
    }
  return count;
}

const Rgb8 white{255, 255, 255};

TEST(Plot, TextUsesTheBitmapFont) {
  Image image(40, 10, white);
  drawText(image, 0, 0, "1", 1, Rgb8{0, 0, 0});
  // '1' has glyph rows 0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E: 1 + 2 + 1 + 1 + 1 + 1 + 3 = 10 dots.
  EXPECT_EQ(countNonWhite(image), 10);
  // Three 5-dot glyphs and two 1-dot gaps, at scale 2; the pen moves one more gap.
  EXPECT_EQ(textWidth("abc", 2), 34);
  EXPECT_EQ(textAdvance("abc", 2), 36);
  Image upper(40, 10, white), lower(40, 10, white);
  drawText(upper, 0, 0, "AZ", 1, Rgb8{0, 0, 0});
  drawText(lower, 0, 0, "az", 1, Rgb8{0, 0, 0});
  EXPECT_EQ(upper.pixels, lower.pixels);
}

TEST(Plot, RendersLogLogSeriesWithLegend) {
  PlotSpec spec;
  spec.title = "error vs time";
  spec.xLabel = "time per frame (s)";
  spec.yLabel = "relative L2 error";
  spec.logX = spec.logY = true;
  spec.series.push_back(
      {"backward Euler", {1e-3, 1e-2, 1e-1}, {0.5, 0.1, 0.02}, paletteColor(0), Marker::circle, true});
  spec.series.push_back({"async", {3e-3}, {0.03}, paletteColor(1), Marker::square, false});
  spec.series.push_back(
      {"skipped", {-1.0, 0.0}, {1.0, 1.0}, paletteColor(2), Marker::cross, false});  // not drawable on log axes
  const Image image = renderPlot(spec, 800, 500);
  EXPECT_EQ(image.width, 800);
  EXPECT_GT(countNonWhite(image), 2000);
  // Corner of the frame is black.
  EXPECT_EQ(image.at(80, 50).r, 0);
}

}  // namespace
}  // namespace asyncfem
