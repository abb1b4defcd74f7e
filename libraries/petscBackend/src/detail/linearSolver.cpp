// SPDX-License-Identifier: BSD-3-Clause
#include "detail/linearSolver.hpp"

#include <algorithm>

#include "detail/petscCall.hpp"

namespace asyncfem::detail {

namespace {

void setSolverTypes(KSP ksp, PetscSolverKind kind) {
  PC pc = nullptr;
  checkPetsc(KSPGetPC(ksp, &pc), "KSPGetPC");
  switch (kind) {
    case PetscSolverKind::cgGamg:
      checkPetsc(KSPSetType(ksp, KSPCG), "KSPSetType");
      checkPetsc(PCSetType(pc, PCGAMG), "PCSetType(gamg)");
      break;
    case PetscSolverKind::cgHypre:
      checkPetsc(KSPSetType(ksp, KSPCG), "KSPSetType");
      checkPetsc(PCSetType(pc, PCHYPRE), "PCSetType(hypre)");
      checkPetsc(PCHYPRESetType(pc, "boomeramg"), "PCHYPRESetType");
      break;
    case PetscSolverKind::mumps:
      checkPetsc(KSPSetType(ksp, KSPPREONLY), "KSPSetType");
      checkPetsc(PCSetType(pc, PCCHOLESKY), "PCSetType(cholesky)");
      checkPetsc(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS), "PCFactorSetMatSolverType(mumps)");
      break;
  }
}

// After the options database: CG measures the unpreconditioned residual, so
// relativeTolerance bounds |b - A x| / |b| whatever the preconditioner (unless the
// options chose a norm or another KSP); iterative KSPs start from the previous solution.
void setNormAndInitialGuess(KSP ksp) {
  KSPType type = nullptr;
  checkPetsc(KSPGetType(ksp, &type), "KSPGetType");
  const char* prefix = nullptr;
  checkPetsc(KSPGetOptionsPrefix(ksp, &prefix), "KSPGetOptionsPrefix");
  PetscOptions options = nullptr;
  checkPetsc(PetscObjectGetOptions(reinterpret_cast<PetscObject>(ksp), &options), "PetscObjectGetOptions");
  PetscBool normChosen = PETSC_FALSE;
  checkPetsc(PetscOptionsHasName(options, prefix, "-ksp_norm_type", &normChosen), "PetscOptionsHasName");
  PetscBool isCg = PETSC_FALSE;
  checkPetsc(PetscStrcmp(type, KSPCG, &isCg), "PetscStrcmp");
  if (isCg == PETSC_TRUE && normChosen == PETSC_FALSE) {
    checkPetsc(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED), "KSPSetNormType");
  }
  PetscBool isPreonly = PETSC_FALSE;
  checkPetsc(PetscStrcmp(type, KSPPREONLY, &isPreonly), "PetscStrcmp");
  if (isPreonly == PETSC_FALSE) checkPetsc(KSPSetInitialGuessNonzero(ksp, PETSC_TRUE), "KSPSetInitialGuessNonzero");
}

}  // namespace

OptionsHandle makeSolverOptions(const std::string& options) {
  OptionsHandle database;
  checkPetsc(PetscOptionsCreate(database.out()), "PetscOptionsCreate");
  checkPetsc(PetscOptionsInsertString(database.get(), options.c_str()), "PetscOptionsInsertString");
  char* global = nullptr;
  checkPetsc(PetscOptionsGetAll(nullptr, &global), "PetscOptionsGetAll");
  const PetscErrorCode code = PetscOptionsInsertString(database.get(), global);
  PetscFree(global);
  checkPetsc(code, "PetscOptionsInsertString");
  return database;
}

LinearSolver::LinearSolver(MPI_Comm comm, PetscOptions options, const PetscSolverSettings& settings,
                           const std::string& prefix, Mat fixedOperator) {
  checkPetsc(KSPCreate(comm, ksp_.out()), "KSPCreate");
  checkPetsc(PetscObjectSetOptions(reinterpret_cast<PetscObject>(ksp_.get()), options), "PetscObjectSetOptions");
  if (!prefix.empty()) checkPetsc(KSPSetOptionsPrefix(ksp_.get(), prefix.c_str()), "KSPSetOptionsPrefix");
  if (fixedOperator != nullptr) {
    checkPetsc(MatSetOption(fixedOperator, MAT_SPD, PETSC_TRUE), "MatSetOption(MAT_SPD)");
    checkPetsc(KSPSetOperators(ksp_.get(), fixedOperator, fixedOperator), "KSPSetOperators");
  }
  setSolverTypes(ksp_.get(), settings.kind);
  const PetscReal absolute = settings.absoluteTolerance > 0.0 ? settings.absoluteTolerance : 0.0;
  checkPetsc(KSPSetTolerances(ksp_.get(), settings.relativeTolerance, absolute, PETSC_DEFAULT, settings.maxIterations),
             "KSPSetTolerances");
  checkPetsc(KSPSetFromOptions(ksp_.get()), "KSPSetFromOptions");
  setNormAndInitialGuess(ksp_.get());
}

void LinearSolver::setOperator(Mat matrix) {
  checkPetsc(MatSetOption(matrix, MAT_SPD, PETSC_TRUE), "MatSetOption(MAT_SPD)");
  checkPetsc(KSPSetOperators(ksp_.get(), matrix, matrix), "KSPSetOperators");
}

void LinearSolver::setOperators(Mat matrix, Mat preconditioning) {
  checkPetsc(MatSetOption(matrix, MAT_SPD, PETSC_TRUE), "MatSetOption(MAT_SPD)");
  checkPetsc(MatSetOption(preconditioning, MAT_SPD, PETSC_TRUE), "MatSetOption(MAT_SPD)");
  checkPetsc(KSPSetOperators(ksp_.get(), matrix, preconditioning), "KSPSetOperators");
}

void LinearSolver::setUp() { checkPetsc(KSPSetUp(ksp_.get()), "KSPSetUp"); }

SolveOutcome LinearSolver::solve(Vec b, Vec x) {
  checkPetsc(KSPSolve(ksp_.get(), b, x), "KSPSolve");
  KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
  checkPetsc(KSPGetConvergedReason(ksp_.get(), &reason), "KSPGetConvergedReason");
  PetscInt iterations = 0;
  checkPetsc(KSPGetIterationNumber(ksp_.get(), &iterations), "KSPGetIterationNumber");
  SolveOutcome outcome;
  outcome.iterations = static_cast<int>(iterations);
  outcome.converged = reason >= 0;
  if (!outcome.converged) {
    const char* text = nullptr;
    KSPGetConvergedReasonString(ksp_.get(), &text);
    outcome.reason = text ? text : "diverged";
  }
  return outcome;
}

void LinearSolver::applyPreconditioner(Vec b, Vec x) {
  checkPetsc(KSPSetUp(ksp_.get()), "KSPSetUp");
  PC pc = nullptr;
  checkPetsc(KSPGetPC(ksp_.get(), &pc), "KSPGetPC");
  checkPetsc(PCApply(pc, b, x), "PCApply");
}

std::string LinearSolver::kspType() const {
  KSPType type = nullptr;
  checkPetsc(KSPGetType(ksp_.get(), &type), "KSPGetType");
  return type ? type : "";
}

std::string LinearSolver::pcType() const {
  PC pc = nullptr;
  checkPetsc(KSPGetPC(ksp_.get(), &pc), "KSPGetPC");
  PCType type = nullptr;
  checkPetsc(PCGetType(pc, &type), "PCGetType");
  return type ? type : "";
}

}  // namespace asyncfem::detail
