// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <mpi.h>
#include <petscsys.h>

#include <cstddef>
#include <functional>

namespace asyncfem::detail {

/// Makes PETSc report errors to checkPetsc() instead of printing them (installed by
/// PetscRuntime; idempotent).
void installPetscErrorHandler();

/// Throws asyncfem::Error "PETSc: CALL failed: MESSAGE" when code is not 0, with the
/// message PETSc's error handler recorded for it.
void checkPetsc(PetscErrorCode code, const char* call);

/// Runs rank-local work (element computations, user callbacks, input checks) so that a
/// failure on any rank reaches every rank: each rank runs work and catches what it
/// throws, then all ranks agree (one MPI_Allreduce) on the lowest failing rank, which
/// broadcasts its message; every rank then throws the same exception type
/// (ValidationError, NumericalError or Error) with "rank R: MESSAGE". No rank is left
/// waiting in a later collective call. Collective over comm; work must not call
/// collective operations itself.
void collectively(MPI_Comm comm, const std::function<void()>& work);

/// Sums count doubles over the ranks of comm in place (MPI_Allreduce); collective. Throws
/// asyncfem::Error if MPI reports a failure.
void sumOverRanks(MPI_Comm comm, double* values, std::size_t count);

}  // namespace asyncfem::detail
