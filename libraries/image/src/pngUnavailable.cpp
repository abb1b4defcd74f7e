// SPDX-License-Identifier: BSD-3-Clause
// Built when libpng was not found: every PNG call is an error that says why.
#include <asyncfem/core/error.hpp>
#include <asyncfem/image/png.hpp>
#include <string>

namespace asyncfem {

namespace {

[[noreturn]] void noPng(const std::filesystem::path& path, const char* what) {
  throw Error(path.string() + ": cannot " + what +
              " PNG: this build of AsyncFEM has no PNG support (libpng was not found when it was configured; "
              "install libpng-dev and configure again)");
}

}  // namespace

bool pngSupported() { return false; }

void writePng(const std::filesystem::path& path, const Image& /*image*/, PngCompression /*compression*/) {
  noPng(path, "write");
}

Image readPng(const std::filesystem::path& path) { noPng(path, "read"); }

}  // namespace asyncfem
