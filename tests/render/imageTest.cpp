// SPDX-License-Identifier: BSD-3-Clause
// The image library: Image, lines, PNG files, the bitmap font and side-by-side composition.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/image/png.hpp>
#include <asyncfem/image/text.hpp>
#include <fstream>

#include "renderTestHelpers.hpp"

namespace {

using namespace asyncfem;

Image gradient(int width, int height) {
  Image image(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      std::uint8_t* p = image.pixel(x, y);
      p[0] = static_cast<std::uint8_t>(x * 7);
      p[1] = static_cast<std::uint8_t>(y * 11);
      p[2] = static_cast<std::uint8_t>((x * y) % 256);
    }
  }
  return image;
}

TEST(Image, ColoursConvertToBytesByRounding) {
  // 0.5 * 255 = 127.5 rounds away from zero; out-of-range components clamp.
  EXPECT_EQ(toRgb8(Eigen::Vector3f(0.5F, -1.0F, 2.0F)), (Rgb8{128, 0, 255}));
  const Image a(3, 2, Eigen::Vector3f(0.2F, 0.4F, 0.6F));
  const Image b(3, 2, Rgb8{51, 102, 153});
  EXPECT_TRUE(a == b);
  EXPECT_EQ(a.at(2, 1), (Rgb8{51, 102, 153}));
  EXPECT_THROW(Image(-1, 4), Error);
}

TEST(Image, LinesCoverBothEndsAndClip) {
  Image image(10, 10, Rgb8{255, 255, 255});
  const Rgb8 black{0, 0, 0};
  drawLine(image, 1, 1, 8, 1, black);
  for (int x = 0; x < 10; ++x) {
    EXPECT_EQ(image.at(x, 1) == black, x >= 1 && x <= 8) << x;
  }
  // A diagonal with a 2-pixel pen: the pen covers [x, x + 1] x [y, y + 1] at each step.
  Image thick(10, 10, Rgb8{255, 255, 255});
  drawLine(thick, 2, 2, 5, 5, black, 2);
  int lit = 0;
  for (int y = 0; y < 10; ++y) {
    for (int x = 0; x < 10; ++x) {
      lit += thick.at(x, y) == black ? 1 : 0;
    }
  }
  EXPECT_EQ(lit, 4 + (3 * 3));  // the first 2 x 2 square, then 3 new pixels per step
  // Far outside the image: nothing drawn, nothing written out of bounds.
  Image clipped(4, 4, Rgb8{255, 255, 255});
  drawLine(clipped, -1000000, -5, 1000000, -5, black, 3);
  EXPECT_TRUE(clipped == Image(4, 4, Rgb8{255, 255, 255}));
}

TEST(Png, ThisBuildHasPngSupport) {
  // Rendering needs libpng (the top-level CMakeLists requires it with ASYNCFEM_WITH_RENDER).
  EXPECT_TRUE(pngSupported());
}

TEST(Png, RoundTripIsExact) {
  const auto folder = asyncfem::renderTesting::freshFolder("png");
  for (const auto compression : {PngCompression::fast, PngCompression::standard}) {
    const Image image = gradient(37, 23);
    writePng(folder / "a.png", image, compression);
    EXPECT_TRUE(readPng(folder / "a.png") == image);
  }
  // No temporary file is left behind.
  int files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(folder)) {
    ++files;
  }
  EXPECT_EQ(files, 1);
  std::filesystem::remove_all(folder);
}

TEST(Png, ErrorsNameTheFile) {
  const auto folder = asyncfem::renderTesting::freshFolder("pngErrors");
  try {
    readPng(folder / "missing.png");
    FAIL() << "expected Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.png"), std::string::npos) << e.what();
  }
  std::ofstream(folder / "bad.png") << "not a png";
  EXPECT_THROW(readPng(folder / "bad.png"), Error);
  try {
    writePng(folder / "no" / "such" / "folder.png", gradient(4, 4));
    FAIL() << "expected Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("folder.png"), std::string::npos) << e.what();
  }
  EXPECT_THROW(writePng(folder / "empty.png", Image{}), Error);
  std::filesystem::remove_all(folder);
}

TEST(Text, GlyphsDrawInsideTheirCell) {
  Image image(100, 20, Eigen::Vector3f::Zero());
  EXPECT_EQ(textWidth("AB1", 2), ((3 * 6) - 1) * 2);
  EXPECT_EQ(textWidth("", 3), 0);
  drawText(image, 3, 4, "AB1", 2, Eigen::Vector3f::Ones());
  int lit = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      if (image.pixel(x, y)[0] != 0) {
        ++lit;
        EXPECT_GE(x, 3);
        EXPECT_LT(x, 3 + textWidth("AB1", 2));
        EXPECT_GE(y, 4);
        EXPECT_LT(y, 4 + (glyphHeight * 2));
      }
    }
  }
  EXPECT_GT(lit, 40);
  // Lower case draws as upper case; different letters differ.
  Image upper(40, 10);
  Image lower(40, 10);
  Image other(40, 10);
  drawText(upper, 0, 0, "ASYNC", 1, Eigen::Vector3f::Ones());
  drawText(lower, 0, 0, "async", 1, Eigen::Vector3f::Ones());
  drawText(other, 0, 0, "SINGL", 1, Eigen::Vector3f::Ones());
  EXPECT_TRUE(upper == lower);
  EXPECT_FALSE(upper == other);
  // Brackets, caret and bar have glyphs; a character without one draws as a hollow box.
  for (const char* defined : {"[", "]", "^", "|"}) {
    Image drawn(6, 8);
    Image box(6, 8);
    drawText(drawn, 0, 0, defined, 1, Rgb8{255, 255, 255});
    drawText(box, 0, 0, "~", 1, Rgb8{255, 255, 255});
    EXPECT_FALSE(drawn == box) << defined;
    EXPECT_FALSE(drawn == Image(6, 8)) << defined;
  }
}

TEST(Text, SideBySideKeepsBothImagesUnderTheirBars) {
  const Image left = gradient(30, 20);
  Image right(40, 20, Eigen::Vector3f(0.0F, 1.0F, 0.0F));
  const Image both = composeSideBySide({left, right}, {"async", "single-rate"}, 12);
  EXPECT_EQ(both.width, 70);
  EXPECT_EQ(both.height, 32);
  EXPECT_EQ(std::vector<std::uint8_t>(both.pixel(0, 12), both.pixel(0, 12) + 3),
            std::vector<std::uint8_t>(left.pixel(0, 0), left.pixel(0, 0) + 3));
  EXPECT_EQ(both.pixel(69, 31)[1], 255);
  EXPECT_EQ(both.pixel(69, 31)[0], 0);
  // The bars carry white label text.
  int white = 0;
  for (int y = 0; y < 12; ++y) {
    for (int x = 0; x < 70; ++x) {
      white += both.pixel(x, y)[0] == 255 && both.pixel(x, y)[1] == 255 && both.pixel(x, y)[2] == 255 ? 1 : 0;
    }
  }
  EXPECT_GT(white, 20);
  EXPECT_EQ(composeSideBySide({left, right}, {}, 12).height, 20);
  EXPECT_THROW(composeSideBySide({left, right}, {"one"}, 12), Error);
  EXPECT_THROW(composeSideBySide({left, gradient(5, 6)}, {}, 12), Error);
}

}  // namespace
