// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <string>

#include "detail/solverBase.hpp"

namespace asyncfem {

namespace {
constexpr SolverKind kAllKinds[] = {SolverKind::cholmod, SolverKind::umfpack, SolverKind::eigenLDLT,
                                    SolverKind::eigenLU};
}  // namespace

std::string toString(SolverKind kind) {
  switch (kind) {
    case SolverKind::cholmod:
      return "cholmod";
    case SolverKind::umfpack:
      return "umfpack";
    case SolverKind::eigenLDLT:
      return "eigen-ldlt";
    case SolverKind::eigenLU:
      return "eigen-lu";
  }
  throw Error("toString: invalid SolverKind value " + std::to_string(static_cast<int>(kind)));
}

SolverKind parseSolverKind(const std::string& name) {
  std::string valid;
  for (SolverKind kind : kAllKinds) {
    if (toString(kind) == name) return kind;
    valid += (valid.empty() ? "" : ", ") + toString(kind);
  }
  throw Error("unknown sparse solver '" + name + "' (valid: " + valid + ")");
}

std::unique_ptr<SparseSolver> makeSparseSolver(SolverKind kind) {
  switch (kind) {
    case SolverKind::cholmod:
      return detail::makeCholmodSolver();
    case SolverKind::umfpack:
      return detail::makeUmfpackSolver();
    case SolverKind::eigenLDLT:
      return detail::makeEigenLDLTSolver();
    case SolverKind::eigenLU:
      return detail::makeEigenLUSolver();
  }
  throw Error("makeSparseSolver: invalid SolverKind value " + std::to_string(static_cast<int>(kind)));
}

}  // namespace asyncfem
