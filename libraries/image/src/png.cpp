// SPDX-License-Identifier: BSD-3-Clause
// PNG files through libpng's simplified API (png_image), which reports errors through
// return values and png_image::message instead of longjmp.
#include <png.h>
#include <unistd.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/image/png.hpp>
#include <atomic>
#include <cstring>
#include <string>
#include <system_error>

namespace asyncfem {

bool pngSupported() { return true; }

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
