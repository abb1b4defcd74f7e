// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/petscBackend/solverSettings.hpp>

namespace asyncfem {

std::string toString(PetscSolverKind kind) {
  switch (kind) {
    case PetscSolverKind::cgGamg:
      return "cg-gamg";
    case PetscSolverKind::cgHypre:
      return "cg-hypre";
    case PetscSolverKind::mumps:
      return "mumps";
  }
  return "unknown";
}

PetscSolverKind parsePetscSolverKind(const std::string& name) {
  for (PetscSolverKind kind : {PetscSolverKind::cgGamg, PetscSolverKind::cgHypre, PetscSolverKind::mumps}) {
    if (toString(kind) == name) return kind;
  }
  throw ValidationError("unknown PETSc solver '" + name + "' (expected cg-gamg, cg-hypre or mumps)");
}

}  // namespace asyncfem
