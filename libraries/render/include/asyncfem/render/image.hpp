// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <vector>

namespace asyncfem {

/// An 8-bit RGB image, rows from top to bottom, pixels left to right, three bytes each.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  ///< 3 * width * height bytes

  Image() = default;
  /// A width x height image filled with one colour (components in [0, 1]).
  Image(int width, int height, const Eigen::Vector3f& color = Eigen::Vector3f::Zero());

  std::uint8_t* pixel(int x, int y) { return pixels.data() + (3 * ((static_cast<std::size_t>(y) * width) + x)); }
  const std::uint8_t* pixel(int x, int y) const {
    return pixels.data() + (3 * ((static_cast<std::size_t>(y) * width) + x));
  }
  /// Sets pixel (x, y) if it lies inside the image (components in [0, 1]).
  void setPixel(int x, int y, const Eigen::Vector3f& color);
  /// Fills the rectangle [x0, x1) x [y0, y1), clipped to the image.
  void fillRectangle(int x0, int y0, int x1, int y1, const Eigen::Vector3f& color);
  /// Copies source into this image with its top-left corner at (x, y), clipped.
  void paste(const Image& source, int x, int y);

  bool operator==(const Image&) const = default;
};

/// How hard writePng compresses: fast (zlib level 1-ish filters; what the frame renderer
/// uses) or the library default (smaller files, slower).
enum class PngCompression { fast, standard };

/// Writes image as an 8-bit RGB PNG through libpng. The data go to a temporary file next
/// to path, which is then renamed over path, so readers never see a partial PNG. Throws
/// asyncfem::Error naming the file when it cannot be written.
void writePng(const std::filesystem::path& path, const Image& image, PngCompression compression = PngCompression::fast);

/// Reads a PNG (any colour type libpng converts) as 8-bit RGB. Throws asyncfem::Error
/// naming the file when it is missing or not a readable PNG.
Image readPng(const std::filesystem::path& path);

}  // namespace asyncfem
