// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

namespace asyncfem {

/// Element partition of a tet mesh into numParts parts: METIS's dual-graph k-way
/// partition (METIS_PartMeshDual, elements adjacent when they share a face), which
/// keeps parts balanced in element count and cuts few faces. Returns numElements part
/// ids in [0, numParts); numParts = 1 returns all zeros without calling METIS.
/// Deterministic (METIS's default seed). Throws ValidationError for numParts < 1 or an
/// empty mesh when numParts > 1, asyncfem::Error if METIS fails.
std::vector<int> partitionElements(const TetMesh& mesh, int numParts);

}  // namespace asyncfem
