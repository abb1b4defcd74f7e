// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/image/image.hpp>
#include <filesystem>

namespace asyncfem {

/// True when this build reads and writes PNG files (libpng was found when AsyncFEM was
/// configured); otherwise writePng and readPng throw asyncfem::Error.
bool pngSupported();

/// How hard writePng compresses: fast (what the frame renderer uses: its frames are
/// written as fast as they are drawn) or the library default (smaller files, slower).
enum class PngCompression { fast, standard };

/// Writes image as an 8-bit RGB PNG through libpng. The data go to a temporary file next
/// to path, which is then renamed over path, so readers never see a partial PNG. Throws
/// asyncfem::Error naming the file when it cannot be written, when the image is empty or
/// inconsistent, or when the build has no PNG support.
void writePng(const std::filesystem::path& path, const Image& image, PngCompression compression = PngCompression::fast);

/// Reads a PNG (any colour type libpng converts) as 8-bit RGB. Throws asyncfem::Error
/// naming the file when it is missing or not a readable PNG, or when the build has no PNG
/// support.
Image readPng(const std::filesystem::path& path);

}  // namespace asyncfem
