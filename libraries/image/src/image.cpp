// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/image/image.hpp>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>

namespace asyncfem {

namespace {

std::uint8_t toByte(float value) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(value, 0.0F, 1.0F) * 255.0F));
}

}  // namespace

Rgb8 toRgb8(const Eigen::Vector3f& color) { return {toByte(color.x()), toByte(color.y()), toByte(color.z())}; }

Image::Image(int width_, int height_, const Eigen::Vector3f& color) : Image(width_, height_, toRgb8(color)) {}

Image::Image(int width_, int height_, Rgb8 color) : width(width_), height(height_) {
  if (width < 0 || height < 0) {
    throw Error("Image: negative size " + std::to_string(width) + " x " + std::to_string(height));
  }
  pixels.resize(3 * static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  fillRectangle(0, 0, width, height, color);
}

void Image::setPixel(int x, int y, Rgb8 color) {
  if (x < 0 || y < 0 || x >= width || y >= height) {
    return;
  }
  std::uint8_t* p = pixel(x, y);
  p[0] = color.r;
  p[1] = color.g;
  p[2] = color.b;
}

void Image::fillRectangle(int x0, int y0, int x1, int y1, Rgb8 color) {
  x0 = std::max(x0, 0);
  y0 = std::max(y0, 0);
  x1 = std::min(x1, width);
  y1 = std::min(y1, height);
  const std::uint8_t rgb[3] = {color.r, color.g, color.b};
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) {
      std::memcpy(pixel(x, y), rgb, 3);
    }
  }
}

void Image::paste(const Image& source, int x, int y) {
  const int xStart = std::max(0, -x);
  const int xEnd = std::min(source.width, width - x);
  if (xEnd <= xStart) {
    return;
  }
  for (int row = std::max(0, -y); row < std::min(source.height, height - y); ++row) {
    std::memcpy(pixel(x + xStart, y + row), source.pixel(xStart, row), 3 * static_cast<std::size_t>(xEnd - xStart));
  }
}

void drawLine(Image& image, int x0, int y0, int x1, int y1, Rgb8 color, int thickness) {
  const int dx = std::abs(x1 - x0);
  const int dy = -std::abs(y1 - y0);
  const int stepX = x0 < x1 ? 1 : -1;
  const int stepY = y0 < y1 ? 1 : -1;
  int error = dx + dy;
  // The pen covers [x - below, x + above] around each point of the segment.
  const int below = (thickness - 1) / 2;
  const int above = thickness / 2;
  for (int position = 0; position < 100000; ++position) {
    image.fillRectangle(x0 - below, y0 - below, x0 + above + 1, y0 + above + 1, color);
    if (x0 == x1 && y0 == y1) {
      break;
    }
    const int twice = 2 * error;
    if (twice >= dy) {
      error += dy;
      x0 += stepX;
    }
    if (twice <= dx) {
      error += dx;
      y0 += stepY;
    }
  }
}

}  // namespace asyncfem
