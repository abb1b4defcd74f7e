// SPDX-License-Identifier: BSD-3-Clause
// PNG output through libpng (built when ASYNCFEM_WITH_RENDER is ON).
#include "pngWriter.hpp"

#include <png.h>

#include <asyncfem/core/error.hpp>
#include <cstdio>
#include <memory>
#include <vector>

namespace asyncfem::bench {

bool pngSupported() { return true; }

void writePng(const std::filesystem::path& path, const Image& image) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "wb"), &std::fclose);
  if (!file) throw Error(path.string() + ": cannot open for writing");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) throw Error(path.string() + ": libpng could not start");
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    throw Error(path.string() + ": libpng could not start");
  }
  // libpng reports errors by longjmp; nothing with a destructor is created below it.
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw Error(path.string() + ": libpng failed while writing");
  }
  png_init_io(png, file.get());
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.width()), static_cast<png_uint_32>(image.height()), 8,
               PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  const std::vector<std::uint8_t>& pixels = image.pixels();
  const std::size_t stride = static_cast<std::size_t>(image.width()) * 3;
  for (int y = 0; y < image.height(); ++y) {
    png_write_row(png, const_cast<png_bytep>(pixels.data() + static_cast<std::size_t>(y) * stride));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
}

}  // namespace asyncfem::bench
