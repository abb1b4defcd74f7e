// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <mpi.h>
#include <petscsys.h>

#include <array>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

namespace asyncfem::detail {

/// Who owns what in a distributed run, computed identically on every rank from the
/// (replicated) mesh, the fixed vertices and the element partition.
///
/// Numbering: a free vertex is a "block" of three DOFs. Vertex v belongs to the lowest
/// rank among the parts of its elements; blocks are numbered rank by rank, each rank's
/// vertices in ascending id order, so rank r owns the contiguous block range
/// [blockStart[r], blockStart[r + 1]) and global DOF 3 b + c. Fixed vertices get -1.
struct DistributedLayout {
  int rank = 0;
  int numRanks = 1;
  std::vector<int> localElements;     ///< element ids of this rank's part, ascending
  std::vector<int> elementsPerRank;   ///< part sizes
  std::vector<PetscInt> vertexBlock;  ///< numVertices: global block, -1 for fixed vertices
  std::vector<int> blockVertex;       ///< numBlocks: the vertex of each block
  std::vector<PetscInt> blockStart;   ///< numRanks + 1
  PetscInt firstBlock = 0;            ///< = blockStart[rank]
  PetscInt ownedBlocks = 0;
  PetscInt numBlocks = 0;
  /// Global DOFs of free vertices of local elements owned elsewhere (three per vertex,
  /// ascending): the ghost entries of the displacement.
  std::vector<PetscInt> ghostDofs;
  /// DOFs of one element: 12 for a tetrahedron, 24 for a hexahedron.
  int dofsPerElement = 12;
  /// Per local element, its global DOFs (-1 for fixed ones) and their indices in the
  /// ghosted displacement's local form (owned first, then ghosts; -1 for fixed); the first
  /// dofsPerElement entries are used.
  std::vector<std::array<PetscInt, 24>> elementDofs;
  std::vector<std::array<PetscInt, 24>> elementLocalDofs;
  /// Per owned block row: the number of non-zero 3x3 blocks in the columns this rank
  /// owns and in the others (exact preallocation of the system matrices).
  std::vector<PetscInt> diagonalBlocks;
  std::vector<PetscInt> offDiagonalBlocks;
};

/// Builds the layout. fixedVertices: any order, duplicates allowed. elementPart:
/// numElements part ids in [0, numRanks). Throws ValidationError naming a fixed vertex
/// out of range or a free vertex that no element uses (its rows would be zero).
DistributedLayout buildDistributedLayout(const TetMesh& mesh, const std::vector<int>& fixedVertices,
                                         const std::vector<int>& elementPart, int rank, int numRanks);

/// METIS's element partition of mesh into the ranks of comm (partitionElements()),
/// computed on rank 0 and broadcast, so every rank holds the same parts whatever METIS
/// does (all zeros on one rank). Collective; a METIS failure throws on every rank.
std::vector<int> elementPartsOnEveryRank(const TetMesh& mesh, MPI_Comm comm);

}  // namespace asyncfem::detail
