// SPDX-License-Identifier: BSD-3-Clause
// Writing plot images: libpng when the build has it (ASYNCFEM_WITH_RENDER), else nothing.
#pragma once

#include <asyncfem/benchmarkTools/plot.hpp>
#include <filesystem>

namespace asyncfem::bench {

/// True when this build can write PNG files (libpng was found: ASYNCFEM_WITH_RENDER=ON).
bool pngSupported();
/// Writes image as an 8-bit RGB PNG. Throws asyncfem::Error when the file cannot be
/// written or the build has no PNG support (check pngSupported() first).
void writePng(const std::filesystem::path& path, const Image& image);

}  // namespace asyncfem::bench
