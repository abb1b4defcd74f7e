// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/petscBackend/solverSettings.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
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
};

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
/// (AsyncOptions::largeSystemSolver, whose type this is) for a run on mesh: every rank runs
/// the integrator on the replicated state, and H^{LL*} is solved distributed. Rows (global
/// DOF ids 3 v + c) are owned by their vertex's rank in METIS's element partition of mesh
/// (partitionElements(), computed on rank 0 and broadcast; a vertex belongs to the lowest
/// rank among its elements'), so each rank's rows are a compact piece of the mesh; GAMG
/// gets the rigid-body modes. Collective; needs a live PetscRuntime, which must outlive
/// every solver made.
std::function<std::unique_ptr<SparseSolver>(const std::vector<int>& largeDofs)> makePetscLargeSystemSolver(
    const TetMesh& mesh, const PetscSolverSettings& settings, std::shared_ptr<PetscSolveCounts> totals = {});

}  // namespace asyncfem
