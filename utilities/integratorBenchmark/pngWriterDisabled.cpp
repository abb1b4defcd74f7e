// SPDX-License-Identifier: BSD-3-Clause
// Builds without libpng (ASYNCFEM_WITH_RENDER=OFF): no PNG output; the benchmark writes
// its CSV files only and says so.
#include <asyncfem/core/error.hpp>

#include "pngWriter.hpp"

namespace asyncfem::bench {

bool pngSupported() { return false; }

void writePng(const std::filesystem::path& path, const Image& /*image*/) {
  throw Error(path.string() + ": this build has no PNG support (configure with ASYNCFEM_WITH_RENDER=ON)");
}

}  // namespace asyncfem::bench
