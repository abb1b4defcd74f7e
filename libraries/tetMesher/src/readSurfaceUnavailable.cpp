// SPDX-License-Identifier: BSD-3-Clause
// readSurface for builds without assimp (ASYNCFEM_WITH_ASSIMP=OFF).
#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/triangleSurface.hpp>

namespace asyncfem {

bool surfaceReaderAvailable() { return false; }

TriangleSurface readSurface(const std::filesystem::path& path) {
  throw Error(path.string() +
              ": cannot read surfaces: this build has no assimp (configure with "
              "-DASYNCFEM_WITH_ASSIMP=ON)");
}

}  // namespace asyncfem
