// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/forceModel/forceModel.hpp>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <memory>

namespace asyncfem {

/// Distributes the element loop of a computation that every rank of MPI_COMM_WORLD runs
/// alike on the same (replicated) state, such as the asynchronous integrator over MPI: the
/// returned model's forcesAndTangent() evaluates only this rank's elements, those of
/// METIS's element partition that makePetscLargeSystemSolver() uses, through the
/// single-process model of physics (its force model type, tangent kind and hyperelastic
/// options) on their sub-mesh, so each element goes through the same kernel as in a local
/// run; it then sums the forces and the tangent's values over the ranks (MPI_Allreduce) so
/// that every rank receives the whole mesh's f_int(u) and K(u), the same on every rank. They
/// differ from wholeMesh's only by the order of the element sums (round-off).
///
/// forcesAndTangent() is collective: every rank calls it with the same displacement. An
/// element failure on one rank (an inverted element) throws the same exception type on
/// every rank, "rank R: ... element E ..." with E the mesh's element id. Every other member
/// forwards to wholeMesh (the same model on the whole mesh, evaluated locally, no
/// communication), so a rank may call them alone: the stable coupling's per-element
/// tangents of a region's owner, a monitor's energy.
///
/// On one rank it returns wholeMesh itself (nothing to distribute or sum).
///
/// mesh must be the mesh wholeMesh was built for (the scene's, materials applied). Throws
/// ValidationError for the linear model (K u needs no element loop) or a null wholeMesh;
/// collective (rank 0 partitions); needs a live PetscRuntime.
std::shared_ptr<ForceModel> makeRankSummedForceModel(const TetMesh& mesh, const ProblemSettings& physics,
                                                     std::shared_ptr<ForceModel> wholeMesh);

}  // namespace asyncfem
