// SPDX-License-Identifier: BSD-3-Clause
#include <metis.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/petscBackend/partition.hpp>
#include <string>

namespace asyncfem {

std::vector<int> partitionElements(const TetMesh& mesh, int numParts) {
  if (numParts < 1)
    throw ValidationError("partitionElements: numParts must be >= 1 (got " + std::to_string(numParts) + ")");
  const int numElements = mesh.numElements();
  std::vector<int> parts(static_cast<std::size_t>(numElements), 0);
  if (numParts == 1) return parts;
  if (numElements == 0) throw ValidationError("partitionElements: the mesh has no elements");

  idx_t elementCount = numElements;
  idx_t vertexCount = mesh.numVertices();
  std::vector<idx_t> elementStart(static_cast<std::size_t>(numElements) + 1);
  const int corners = mesh.verticesPerElement();
  std::vector<idx_t> elementVertices(static_cast<std::size_t>(numElements) * static_cast<std::size_t>(corners));
  for (int e = 0; e < numElements; ++e) {
    elementStart[static_cast<std::size_t>(e)] = corners * e;
    for (int a = 0; a < corners; ++a)
      elementVertices[(static_cast<std::size_t>(corners) * static_cast<std::size_t>(e)) + static_cast<std::size_t>(a)] =
          mesh.elementVertex(e, a);
  }
  elementStart.back() = corners * numElements;
  // Elements are neighbours in the dual graph when they share a face (three vertices of a
  // tetrahedron, four of a hexahedron), so the cut counts interface faces, which is what
  // the assembly communicates over.
  idx_t commonVertices = mesh.isHexahedral() ? 4 : 3;
  idx_t partCount = numParts;
  idx_t cut = 0;
  std::vector<idx_t> elementParts(static_cast<std::size_t>(numElements));
  std::vector<idx_t> vertexParts(static_cast<std::size_t>(vertexCount));
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_NUMBERING] = 0;
  const int status =
      METIS_PartMeshDual(&elementCount, &vertexCount, elementStart.data(), elementVertices.data(), nullptr, nullptr,
                         &commonVertices, &partCount, nullptr, options, &cut, elementParts.data(), vertexParts.data());
  if (status != METIS_OK) {
    throw Error("partitionElements: METIS_PartMeshDual failed (status " + std::to_string(status) + ") for " +
                std::to_string(numElements) + " elements into " + std::to_string(numParts) + " parts");
  }
  for (std::size_t e = 0; e < parts.size(); ++e) parts[e] = static_cast<int>(elementParts[e]);
  return parts;
}

}  // namespace asyncfem
