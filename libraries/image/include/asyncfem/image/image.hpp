// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace asyncfem {

/// An 8-bit RGB colour.
struct Rgb8 {
  std::uint8_t r = 0;
  std::uint8_t g = 0;
  std::uint8_t b = 0;

  bool operator==(const Rgb8&) const = default;
};

/// A colour with components in [0, 1] as bytes: each component clamped to [0, 1], scaled
/// by 255 and rounded to the nearest integer.
Rgb8 toRgb8(const Eigen::Vector3f& color);

/// An 8-bit RGB image, rows from top to bottom, pixels left to right, three bytes each.
/// Every drawing function clips to the image: coordinates outside it are ignored.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  ///< 3 * width * height bytes

  Image() = default;
  /// A width x height image filled with one colour (components in [0, 1]). Throws
  /// asyncfem::Error for a negative size.
  Image(int width, int height, const Eigen::Vector3f& color = Eigen::Vector3f::Zero());
  /// A width x height image filled with one colour.
  Image(int width, int height, Rgb8 color);

  /// The three bytes of pixel (x, y); (x, y) must lie inside the image.
  std::uint8_t* pixel(int x, int y) { return pixels.data() + (3 * ((static_cast<std::size_t>(y) * width) + x)); }
  const std::uint8_t* pixel(int x, int y) const {
    return pixels.data() + (3 * ((static_cast<std::size_t>(y) * width) + x));
  }
  /// The colour of pixel (x, y); (x, y) must lie inside the image.
  Rgb8 at(int x, int y) const {
    const std::uint8_t* p = pixel(x, y);
    return {p[0], p[1], p[2]};
  }
  /// Sets pixel (x, y) if it lies inside the image.
  void setPixel(int x, int y, Rgb8 color);
  void setPixel(int x, int y, const Eigen::Vector3f& color) { setPixel(x, y, toRgb8(color)); }
  /// Fills the rectangle [x0, x1) x [y0, y1), clipped to the image.
  void fillRectangle(int x0, int y0, int x1, int y1, Rgb8 color);
  void fillRectangle(int x0, int y0, int x1, int y1, const Eigen::Vector3f& color) {
    fillRectangle(x0, y0, x1, y1, toRgb8(color));
  }
  /// Copies source into this image with its top-left corner at (x, y), clipped.
  void paste(const Image& source, int x, int y);

  bool operator==(const Image&) const = default;
};

/// Draws the segment from (x0, y0) to (x1, y1), both ends included (Bresenham), with a
/// square pen thickness pixels wide, clipped to the image. At most 100,000 pen positions
/// are drawn, so a segment to a far-off point costs bounded time.
void drawLine(Image& image, int x0, int y0, int x1, int y1, Rgb8 color, int thickness = 1);

}  // namespace asyncfem
