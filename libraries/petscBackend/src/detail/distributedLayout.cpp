// SPDX-License-Identifier: BSD-3-Clause
#include "detail/distributedLayout.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/petscBackend/partition.hpp>
#include <climits>
#include <string>

#include "detail/petscCall.hpp"

namespace asyncfem::detail {

namespace {

std::size_t at(PetscInt i) { return static_cast<std::size_t>(i); }

/// Vertex -> element adjacency in compressed rows: the elements of vertex v are
/// elements[start[v] .. start[v + 1]).
struct VertexElements {
  std::vector<int> start;
  std::vector<int> elements;
};

std::vector<bool> fixedMask(const std::vector<int>& fixedVertices, int numVertices) {
  std::vector<bool> fixed(static_cast<std::size_t>(numVertices), false);
  for (int v : fixedVertices) {
    if (v < 0 || v >= numVertices) {
      throw ValidationError("PETSc backend: fixed vertex " + std::to_string(v) + " is out of range [0, " +
                            std::to_string(numVertices) + ")");
    }
    fixed[static_cast<std::size_t>(v)] = true;
  }
  return fixed;
}

// Part sizes, this rank's elements, each vertex's owner (the lowest part among its
// elements; INT_MAX for none) and the vertex -> element adjacency.
std::vector<int> assignOwners(const TetMesh& mesh, const std::vector<bool>& fixed, const std::vector<int>& elementPart,
                              DistributedLayout& layout, VertexElements& adjacency) {
  const int numVertices = mesh.numVertices();
  const int corners = mesh.verticesPerElement();
  std::vector<int> owner(static_cast<std::size_t>(numVertices), INT_MAX);
  adjacency.start.assign(static_cast<std::size_t>(numVertices) + 1, 0);
  layout.elementsPerRank.assign(static_cast<std::size_t>(layout.numRanks), 0);
  for (int e = 0; e < mesh.numElements(); ++e) {
    const int part = elementPart[static_cast<std::size_t>(e)];
    ++layout.elementsPerRank[static_cast<std::size_t>(part)];
    if (part == layout.rank) layout.localElements.push_back(e);
    for (int a = 0; a < corners; ++a) {
      const auto v = static_cast<std::size_t>(mesh.elementVertex(e, a));
      owner[v] = std::min(owner[v], part);
      ++adjacency.start[v + 1];
    }
  }
  for (int v = 0; v < numVertices; ++v) {
    const auto i = static_cast<std::size_t>(v);
    adjacency.start[i + 1] += adjacency.start[i];
    if (owner[i] == INT_MAX && !fixed[i]) {
      throw ValidationError("PETSc backend: vertex " + std::to_string(v) +
                            " belongs to no element and is not fixed (its rows of M and K would be zero)");
    }
  }
  adjacency.elements.resize(static_cast<std::size_t>(adjacency.start.back()));
  std::vector<int> fill(adjacency.start.begin(), adjacency.start.end() - 1);
  for (int e = 0; e < mesh.numElements(); ++e) {
    for (int a = 0; a < corners; ++a) {
      adjacency.elements[static_cast<std::size_t>(fill[static_cast<std::size_t>(mesh.elementVertex(e, a))]++)] = e;
    }
  }
  return owner;
}

// Blocks rank by rank, ascending vertex id within a rank.
void numberBlocks(const std::vector<bool>& fixed, const std::vector<int>& owner, DistributedLayout& layout) {
  const auto numVertices = static_cast<int>(fixed.size());
  layout.vertexBlock.assign(static_cast<std::size_t>(numVertices), -1);
  layout.blockStart.assign(static_cast<std::size_t>(layout.numRanks) + 1, 0);
  for (int v = 0; v < numVertices; ++v) {
    const auto i = static_cast<std::size_t>(v);
    if (!fixed[i]) ++layout.blockStart[static_cast<std::size_t>(owner[i]) + 1];
  }
  for (int r = 0; r < layout.numRanks; ++r) layout.blockStart[at(r) + 1] += layout.blockStart[at(r)];
  layout.numBlocks = layout.blockStart.back();
  layout.blockVertex.resize(at(layout.numBlocks));
  std::vector<PetscInt> next(layout.blockStart.begin(), layout.blockStart.end() - 1);
  for (int v = 0; v < numVertices; ++v) {
    const auto i = static_cast<std::size_t>(v);
    if (fixed[i]) continue;
    const PetscInt block = next[static_cast<std::size_t>(owner[i])]++;
    layout.vertexBlock[i] = block;
    layout.blockVertex[at(block)] = v;
  }
  layout.firstBlock = layout.blockStart[at(layout.rank)];
  layout.ownedBlocks = layout.blockStart[at(layout.rank) + 1] - layout.firstBlock;
}

bool isOwned(const DistributedLayout& layout, PetscInt block) {
  return block >= layout.firstBlock && block < layout.firstBlock + layout.ownedBlocks;
}

// Ghosts (free vertices of local elements owned by another rank) and each local
// element's global and local DOFs.
void numberElementDofs(const TetMesh& mesh, DistributedLayout& layout) {
  const int corners = mesh.verticesPerElement();
  layout.dofsPerElement = 3 * corners;
  std::vector<PetscInt> ghostBlocks;
  for (int e : layout.localElements) {
    for (int a = 0; a < corners; ++a) {
      const PetscInt block = layout.vertexBlock[static_cast<std::size_t>(mesh.elementVertex(e, a))];
      if (block >= 0 && !isOwned(layout, block)) ghostBlocks.push_back(block);
    }
  }
  std::sort(ghostBlocks.begin(), ghostBlocks.end());
  ghostBlocks.erase(std::unique(ghostBlocks.begin(), ghostBlocks.end()), ghostBlocks.end());
  for (PetscInt block : ghostBlocks) {
    for (PetscInt c = 0; c < 3; ++c) layout.ghostDofs.push_back((3 * block) + c);
  }
  const auto localBlock = [&](PetscInt block) -> PetscInt {
    if (isOwned(layout, block)) return block - layout.firstBlock;
    const auto it = std::lower_bound(ghostBlocks.begin(), ghostBlocks.end(), block);
    return layout.ownedBlocks + static_cast<PetscInt>(it - ghostBlocks.begin());
  };
  layout.elementDofs.resize(layout.localElements.size());
  layout.elementLocalDofs.resize(layout.localElements.size());
  for (std::size_t k = 0; k < layout.localElements.size(); ++k) {
    const int e = layout.localElements[k];
    layout.elementDofs[k].fill(-1);
    layout.elementLocalDofs[k].fill(-1);
    for (int a = 0; a < corners; ++a) {
      const PetscInt block = layout.vertexBlock[static_cast<std::size_t>(mesh.elementVertex(e, a))];
      const PetscInt local = block >= 0 ? localBlock(block) : -1;
      for (int c = 0; c < 3; ++c) {
        const auto slot = static_cast<std::size_t>((3 * a) + c);
        layout.elementDofs[k][slot] = block >= 0 ? (3 * block) + c : -1;
        layout.elementLocalDofs[k][slot] = block >= 0 ? (3 * local) + c : -1;
      }
    }
  }
}

// Exact preallocation: the blocks of row vertex v are the free vertices of all elements
// around v, whatever rank assembles them.
void countMatrixBlocks(const TetMesh& mesh, const VertexElements& adjacency, DistributedLayout& layout) {
  const int corners = mesh.verticesPerElement();
  layout.diagonalBlocks.assign(at(layout.ownedBlocks), 0);
  layout.offDiagonalBlocks.assign(at(layout.ownedBlocks), 0);
  std::vector<int> stamp(static_cast<std::size_t>(mesh.numVertices()), -1);
  for (PetscInt row = 0; row < layout.ownedBlocks; ++row) {
    const int v = layout.blockVertex[at(layout.firstBlock + row)];
    const auto vi = static_cast<std::size_t>(v);
    const auto countColumn = [&](int w) {
      const auto wi = static_cast<std::size_t>(w);
      if (stamp[wi] == v) return;
      stamp[wi] = v;
      const PetscInt block = layout.vertexBlock[wi];
      if (block < 0) return;
      (isOwned(layout, block) ? layout.diagonalBlocks : layout.offDiagonalBlocks)[at(row)] += 1;
    };
    countColumn(v);  // the diagonal block is always stored
    for (int k = adjacency.start[vi]; k < adjacency.start[vi + 1]; ++k) {
      const int e = adjacency.elements[static_cast<std::size_t>(k)];
      for (int a = 0; a < corners; ++a) countColumn(mesh.elementVertex(e, a));
    }
  }
}

}  // namespace

DistributedLayout buildDistributedLayout(const TetMesh& mesh, const std::vector<int>& fixedVertices,
                                         const std::vector<int>& elementPart, int rank, int numRanks) {
  DistributedLayout layout;
  layout.rank = rank;
  layout.numRanks = numRanks;
  const std::vector<bool> fixed = fixedMask(fixedVertices, mesh.numVertices());
  VertexElements adjacency;
  const std::vector<int> owner = assignOwners(mesh, fixed, elementPart, layout, adjacency);
  numberBlocks(fixed, owner, layout);
  numberElementDofs(mesh, layout);
  countMatrixBlocks(mesh, adjacency, layout);
  return layout;
}

std::vector<int> elementPartsOnEveryRank(const TetMesh& mesh, MPI_Comm comm) {
  int rank = 0;
  int ranks = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  std::vector<int> parts(static_cast<std::size_t>(mesh.numElements()), 0);
  collectively(comm, [&] {
    if (rank == 0 && ranks > 1) parts = partitionElements(mesh, ranks);
  });
  if (!parts.empty() && ranks > 1) MPI_Bcast(parts.data(), static_cast<int>(parts.size()), MPI_INT, 0, comm);
  return parts;
}

}  // namespace asyncfem::detail
