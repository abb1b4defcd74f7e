// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/enumNames.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <string>

#include "detail/solverBase.hpp"

namespace asyncfem {

namespace {

// Names of the solver kinds, in the order error messages list them.
constexpr EnumName<SolverKind> kSolverNames[] = {{SolverKind::cholmod, "cholmod"},
                                                 {SolverKind::umfpack, "umfpack"},
                                                 {SolverKind::eigenLDLT, "eigen-ldlt"},
                                                 {SolverKind::eigenLU, "eigen-lu"},
                                                 {SolverKind::dense, "dense"}};

}  // namespace

std::string toString(SolverKind kind) {
  if (kind == SolverKind::external) return "external";
  if (const std::optional<std::string_view> name = findEnumName(kSolverNames, kind)) return std::string(*name);
  throw Error("toString: invalid SolverKind value " + std::to_string(static_cast<int>(kind)));
}

SolverKind parseSolverKind(const std::string& name) {
  if (const std::optional<SolverKind> kind = findEnumValue(kSolverNames, name)) return *kind;
  throw Error("unknown sparse solver '" + name + "' (valid: " + joinEnumNames(kSolverNames, ", ", ", ") + ")");
}

std::unique_ptr<SparseSolver> makeSparseSolver(SolverKind kind, FillOrdering ordering) {
  switch (kind) {
    case SolverKind::cholmod:
      return detail::makeCholmodSolver(ordering);
    case SolverKind::umfpack:
      return detail::makeUmfpackSolver();
    case SolverKind::eigenLDLT:
      return detail::makeEigenLDLTSolver();
    case SolverKind::eigenLU:
      return detail::makeEigenLUSolver();
    case SolverKind::dense:
      return detail::makeDenseSolver();
    case SolverKind::external:
      throw Error("makeSparseSolver: an external solver is built by the library that provides it");
  }
  throw Error("makeSparseSolver: invalid SolverKind value " + std::to_string(static_cast<int>(kind)));
}

}  // namespace asyncfem
