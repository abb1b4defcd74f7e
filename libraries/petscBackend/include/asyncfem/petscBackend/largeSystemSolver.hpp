// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/petscBackend/solverSettings.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

namespace asyncfem {

/// Counters of one distributed solver (makePetscSparseSolver) beyond SolverStats.
struct PetscSolveCounts {
  long long solves = 0;
  long long iterations = 0;  ///< KSP iterations summed over the solves (1 per direct solve)
  int lastIterations = 0;
  int ownedRows = 0;  ///< rows of the distributed matrix this rank owns
  /// Entries of this rank's rows in columns another rank owns (the last matrix analysed):
  /// what a product with the matrix communicates.
  long long offRankEntries = 0;
  /// makePetscLargeSystemSolver, the last set-up: region interfaces (merged where they
  /// share a vertex) whose rows one rank owns, and those left split (more vertices than one
  /// rank's share of the mesh's).
  int regionsOnOneRank = 0, regionsSplit = 0;
  /// makePetscRegionDistribution, the last set-up: the regions this rank computes, of all.
  int regionsComputed = 0, regions = 0;
};

/// Owners of a mesh's vertices for ranks ranks, from an element partition (one part per
/// element): each vertex goes to the lowest part among its elements' (a vertex of no
/// element to the last rank). Then each group in keepTogether (vertex ids; groups that
/// share a vertex are merged) with at most maxGroupVertices vertices moves whole to the
/// rank that already owns most of it (ties: the lowest); larger groups stay split.
struct VertexOwners {
  std::vector<int> owner;
  int groupsKept = 0;   ///< merged groups now on one rank
  int groupsSplit = 0;  ///< merged groups over maxGroupVertices, on several ranks
};
VertexOwners assignVertexOwners(const TetMesh& mesh, const std::vector<int>& elementParts, int ranks,
                                const std::vector<std::vector<int>>& keepTogether, int maxGroupVertices);

/// The rank that computes each fast region (vertex ids of its free vertices and of its
/// interface, one list each per region): the rank assignVertexOwners() gives its interface
/// when that lies on one rank, so a region and its rows of L's system share a rank;
/// otherwise (a split interface, or none) the rank owning most of its own vertices by the
/// lowest-part rule (ties: the lowest).
std::vector<int> regionOwners(const TetMesh& mesh, const std::vector<int>& elementParts, int ranks,
                              const std::vector<std::vector<int>>& regionVertices,
                              const std::vector<std::vector<int>>& interfaceVertices, int maxGroupVertices);

/// The members of AsyncOptions::Processes::RegionDistribution for a run on MPI_COMM_WORLD (assign them
/// to options.processes.regionDistribution.ownedRegions and .sum): each region is computed by the
/// rank regionOwners() names, from the same METIS partition and size limit that
/// makePetscLargeSystemSolver() uses, so it owns the region's interface rows too; the sum
/// is MPI_Allreduce. Collective (rank 0 partitions); needs a live PetscRuntime. totals, when
/// given, gets regionsComputed and regions at each set-up.
struct PetscRegionDistribution {
  std::function<std::vector<char>(const std::vector<std::vector<int>>& regionDofs,
                                  const std::vector<std::vector<int>>& interfaceDofs)>
      ownedRegions;
  std::function<void(double* values, std::size_t count)> sum;
};
PetscRegionDistribution makePetscRegionDistribution(const TetMesh& mesh, std::shared_ptr<PetscSolveCounts> totals = {});

/// A SparseSolver whose matrix and right-hand sides are the same on every rank of
/// MPI_COMM_WORLD (replicated), and whose solve is distributed: each rank inserts the rows
/// it owns into a PETSc MATAIJ (MATMPIAIJ on more than one rank) and PETSc's KSP solves it
/// with settings (CG + GAMG, CG + BoomerAMG, or MUMPS's Cholesky; the options database on
/// top); every rank receives the whole solution. Collective: every rank constructs the
/// solver and calls each member in the same order, with the same matrix and right-hand
/// sides. For symmetric positive definite systems (both triangles stored). kind() is
/// SolverKind::external; the factorization statistics count what PETSc's set-up took
/// (factorFlops and factorNonZeros stay 0).
///
/// Rows: with rowVertex (one vertex id per row, the rows of each vertex consecutive) and
/// vertexOwner (the rank of each vertex), row r is owned by vertexOwner[rowVertex[r]];
/// otherwise the rows are split into contiguous, equal ranges. With coordinates (3 x
/// vertices, the rest positions) and every vertex's three rows present, the matrix has
/// block size 3 and the six rigid-body modes as GAMG's near null space.
///
/// totals, when given, accumulates the counters of every solver made with it (ownedRows:
/// the last solver's).
///
/// Errors: a solve that does not converge throws NumericalError on every rank (the
/// convergence reason and the iterations); PETSc failures throw asyncfem::Error.
std::unique_ptr<SparseSolver> makePetscSparseSolver(const PetscSolverSettings& settings,
                                                    std::vector<int> rowVertex = {},
                                                    std::shared_ptr<const std::vector<int>> vertexOwner = {},
                                                    std::shared_ptr<const Eigen::Matrix3Xd> coordinates = {},
                                                    std::shared_ptr<PetscSolveCounts> totals = {});
/// The counters of a solver made by makePetscSparseSolver (nullptr for another solver).
const PetscSolveCounts* petscSolveCounts(const SparseSolver& solver);

/// The solver factory of the asynchronous integrator's L system
/// (AsyncOptions::Processes::largeSystemSolver, whose type this is) for a run on mesh: every rank runs
/// the integrator on the replicated state, and H^{LL*} is solved distributed. Rows (global
/// DOF ids 3 v + c) are owned by their vertex's rank in METIS's element partition of mesh
/// (partitionElements(), computed on rank 0 and broadcast; a vertex belongs to the lowest
/// rank among its elements'), so each rank's rows are a compact piece of the mesh; at each
/// set-up every region's interface vertices are then kept on one rank
/// (assignVertexOwners(), groups up to one rank's share of the mesh's vertices), so the dense
/// block C_i of each region lies in one rank's diagonal block. GAMG gets the rigid-body
/// modes. Collective; needs a live PetscRuntime, which must outlive
/// every solver made.
std::function<std::unique_ptr<SparseSolver>(const std::vector<int>& largeDofs,
                                            const std::vector<std::vector<int>>& interfaceDofs)>
makePetscLargeSystemSolver(const TetMesh& mesh, const PetscSolverSettings& settings,
                           std::shared_ptr<PetscSolveCounts> totals = {});

}  // namespace asyncfem
