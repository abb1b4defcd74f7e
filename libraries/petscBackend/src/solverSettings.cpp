// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/enumNames.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/petscBackend/solverSettings.hpp>

namespace asyncfem {

namespace {
constexpr EnumName<PetscSolverKind> kPetscSolverNames[] = {
    {PetscSolverKind::cgGamg, "cg-gamg"}, {PetscSolverKind::cgHypre, "cg-hypre"}, {PetscSolverKind::mumps, "mumps"}};
}  // namespace

std::string toString(PetscSolverKind kind) {
  return std::string(findEnumName(kPetscSolverNames, kind).value_or("unknown"));
}

PetscSolverKind parsePetscSolverKind(const std::string& name) {
  if (const std::optional<PetscSolverKind> kind = findEnumValue(kPetscSolverNames, name)) return *kind;
  throw ValidationError("unknown PETSc solver '" + name + "' (expected " +
                        joinEnumNames(kPetscSolverNames, ", ", " or ") + ")");
}

}  // namespace asyncfem
