// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/petscBackend/petscRuntime.hpp>

#include "detail/petscCall.hpp"

namespace asyncfem {

PetscRuntime::PetscRuntime(int* argc, char*** argv, const std::string& options) {
  PetscBool initialized = PETSC_FALSE;
  detail::checkPetsc(PetscInitialized(&initialized), "PetscInitialized");
  if (initialized == PETSC_FALSE) {
    // PETSc's own options database (not a help text): nullptr file, nullptr help.
    const PetscErrorCode code = PetscInitialize(argc, argv, nullptr, nullptr);
    if (code != 0) throw Error("PETSc: PetscInitialize failed with error code " + std::to_string(code));
    ownsInitialization_ = true;
  }
  detail::installPetscErrorHandler();
  if (!options.empty())
    detail::checkPetsc(PetscOptionsInsertString(nullptr, options.c_str()), "PetscOptionsInsertString");
  MPI_Comm_rank(PETSC_COMM_WORLD, &rank_);
  MPI_Comm_size(PETSC_COMM_WORLD, &size_);
}

int PetscRuntime::maxOverRanks(int value) const {
  int largest = value;
  MPI_Allreduce(&value, &largest, 1, MPI_INT, MPI_MAX, PETSC_COMM_WORLD);
  return largest;
}

PetscRuntime::~PetscRuntime() {
  if (ownsInitialization_) PetscFinalize();
}

}  // namespace asyncfem
