// SPDX-License-Identifier: BSD-3-Clause
#include <png.h>
#include <unistd.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/render/image.hpp>
#include <atomic>
#include <cmath>
#include <cstring>
#include <string>
#include <system_error>

namespace asyncfem {

namespace {

std::uint8_t toByte(float value) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(value, 0.0F, 1.0F) * 255.0F));
}

}  // namespace

Image::Image(int width_, int height_, const Eigen::Vector3f& color) : width(width_), height(height_) {
  if (width < 0 || height < 0) {
    throw Error("Image: negative size " + std::to_string(width) + " x " + std::to_string(height));
  }
  pixels.resize(3 * static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  fillRectangle(0, 0, width, height, color);
}

void Image::setPixel(int x, int y, const Eigen::Vector3f& color) {
  if (x < 0 || y < 0 || x >= width || y >= height) {
    return;
  }
  std::uint8_t* p = pixel(x, y);
  p[0] = toByte(color.x());
  p[1] = toByte(color.y());
  p[2] = toByte(color.z());
}

void Image::fillRectangle(int x0, int y0, int x1, int y1, const Eigen::Vector3f& color) {
  x0 = std::max(x0, 0);
  y0 = std::max(y0, 0);
  x1 = std::min(x1, width);
  y1 = std::min(y1, height);
  const std::uint8_t rgb[3] = {toByte(color.x()), toByte(color.y()), toByte(color.z())};
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

void writePng(const std::filesystem::path& path, const Image& image, PngCompression compression) {
  if (image.width <= 0 || image.height <= 0 ||
      image.pixels.size() != 3 * static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height)) {
    throw Error(path.string() + ": cannot write an empty or inconsistent image (" + std::to_string(image.width) +
                " x " + std::to_string(image.height) + ")");
  }
  // A name no other writer uses: this process and a per-process counter.
  static std::atomic<unsigned long> counter{0};
  std::filesystem::path temporary = path;
  temporary += ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter.fetch_add(1));

  png_image png;
  std::memset(&png, 0, sizeof(png));
  png.version = PNG_IMAGE_VERSION;
  png.width = static_cast<png_uint_32>(image.width);
  png.height = static_cast<png_uint_32>(image.height);
  png.format = PNG_FORMAT_RGB;
  png.flags = compression == PngCompression::fast ? PNG_IMAGE_FLAG_FAST : 0;
  // The simplified libpng API reports errors through its return value and png.message
  // (no longjmp reaches this code).
  if (png_image_write_to_file(&png, temporary.c_str(), 0, image.pixels.data(), 3 * image.width, nullptr) == 0) {
    const std::string message = png.message;
    png_image_free(&png);
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw Error(path.string() + ": cannot write PNG: " + message);
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw Error(path.string() + ": cannot write PNG: " + error.message());
  }
}

Image readPng(const std::filesystem::path& path) {
  png_image png;
  std::memset(&png, 0, sizeof(png));
  png.version = PNG_IMAGE_VERSION;
  if (png_image_begin_read_from_file(&png, path.c_str()) == 0) {
    const std::string message = png.message;
    png_image_free(&png);
    throw Error(path.string() + ": cannot read PNG: " + message);
  }
  png.format = PNG_FORMAT_RGB;
  Image image;
  image.width = static_cast<int>(png.width);
  image.height = static_cast<int>(png.height);
  image.pixels.resize(PNG_IMAGE_SIZE(png));
  if (png_image_finish_read(&png, nullptr, image.pixels.data(), 0, nullptr) == 0) {
    const std::string message = png.message;
    png_image_free(&png);
    throw Error(path.string() + ": cannot read PNG: " + message);
  }
  return image;
}

}  // namespace asyncfem
