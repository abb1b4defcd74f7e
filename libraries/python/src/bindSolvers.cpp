// SPDX-License-Identifier: BSD-3-Clause
// libraries/sparseSolver: CHOLMOD, UMFPACK and Eigen factorizations behind one interface.

#include <asyncfem/core/threading.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <bindings.hpp>

namespace asyncfem::python {

namespace {

using Sparse = Eigen::SparseMatrix<double>;

// The solver and the size of the matrix it analysed (-1 before), so that a right-hand
// side of the wrong size is a ValueError naming it.
struct Solver {
  std::unique_ptr<SparseSolver> solver;
  Eigen::Index size = -1;
};

void checkSquare(const Sparse& matrix) {
  if (matrix.rows() != matrix.cols()) {
    throw py::value_error("matrix: expected a square matrix, got shape (" + std::to_string(matrix.rows()) + ", " +
                          std::to_string(matrix.cols()) + ")");
  }
}

// analyze_pattern, factorize, compute: a square matrix, then the call without the GIL.
auto matrixStep(void (SparseSolver::*step)(const Sparse&)) {
  return [step](Solver& solver, const Sparse& matrix) {
    checkSquare(matrix);
    if (step != &SparseSolver::factorize) solver.size = matrix.rows();
    py::gil_scoped_release release;
    (solver.solver.get()->*step)(matrix);
  };
}

}  // namespace

void bindSolvers(py::module_& module) {
  py::enum_<SolverKind>(module, "SolverKind",
                        "Sparse solver: cholmod (supernodal Cholesky), umfpack (LU), eigen_ldlt, eigen_lu, dense "
                        "(dense Cholesky, small SPD systems)")
      .value("cholmod", SolverKind::cholmod)
      .value("umfpack", SolverKind::umfpack)
      .value("eigen_ldlt", SolverKind::eigenLDLT)
      .value("eigen_lu", SolverKind::eigenLU)
      .value("dense", SolverKind::dense);
  module.def(
      "blas_threads", [] { return ScopedBlasThreads::currentCount(); },
      "OpenBLAS's thread count as the solvers' guard reads it (the factorizations hold it to one thread, so that "
      "results do not depend on it); 0 where the process has no OpenBLAS");
  module.def("parse_solver_kind", &parseSolverKind, py::arg("name"),
             "'cholmod', 'umfpack', 'eigen-ldlt', 'eigen-lu', 'dense' -> SolverKind");
  module.def(
      "solver_kind_name", [](SolverKind kind) { return toString(kind); }, py::arg("kind"),
      "SolverKind -> its name ('cholmod', ...)");

  py::class_<SolverStats>(module, "SolverStats",
                          "Work of a sparse solver: factor non-zeros, flops, factorizations, solves and their seconds")
      .def_readonly("factor_non_zeros", &SolverStats::factorNonZeros)
      .def_readonly("factor_flops", &SolverStats::factorFlops)
      .def_readonly("solve_flops_per_rhs", &SolverStats::solveFlopsPerRhs)
      .def_readonly("analyses", &SolverStats::analyses)
      .def_readonly("factorizations", &SolverStats::factorizations)
      .def_readonly("solved_right_hand_sides", &SolverStats::solvedRightHandSides)
      .def_readonly("analyze_seconds", &SolverStats::analyzeSeconds)
      .def_readonly("factor_seconds", &SolverStats::factorSeconds)
      .def_readonly("solve_seconds", &SolverStats::solveSeconds);

  py::class_<Solver>(module, "SparseSolver",
                     "Sparse direct solver: analyze_pattern once, factorize when values change, solve often.")
      .def(py::init([](const py::object& kind) {
             const SolverKind parsed =
                 py::isinstance<py::str>(kind) ? parseSolverKind(kind.cast<std::string>()) : kind.cast<SolverKind>();
             return Solver{makeSparseSolver(parsed)};
           }),
           py::arg("kind") = SolverKind::cholmod, "kind: SolverKind or its name ('cholmod', 'umfpack', ...)")
      .def("analyze_pattern", matrixStep(&SparseSolver::analyzePattern), py::arg("matrix"),
           "symbolic analysis (ordering) of the matrix's pattern")
      .def("factorize", matrixStep(&SparseSolver::factorize), py::arg("matrix"),
           "numeric factorization of a matrix with the analysed pattern")
      .def("compute", matrixStep(&SparseSolver::compute), py::arg("matrix"), "analyze_pattern + factorize")
      .def(
          "solve",
          [](Solver& solver, const py::handle& rhs) -> py::object {
            const py::array array = py::module_::import("numpy").attr("asarray")(rhs);
            Eigen::MatrixXd solution;
            if (array.ndim() == 1) {
              const auto b = vectorArgument(rhs, "rhs", solver.size);
              {
                py::gil_scoped_release release;
                solver.solver->solve(asVector(b), solution);
              }
              return py::cast(Eigen::VectorXd(solution.col(0)));
            }
            // (n, k): one right-hand side per column, solved in one call.
            const auto b = matrixArgument(rhs, "rhs", solver.size, array.ndim() == 2 ? array.shape(1) : 1);
            const Eigen::MatrixXd columns = asRowMatrix(b);
            {
              py::gil_scoped_release release;
              solver.solver->solve(columns, solution);
            }
            return py::cast(solution);
          },
          py::arg("rhs"), "x with A x = rhs; rhs of shape (n,) or (n, k)")
      .def_property_readonly("kind", [](const Solver& solver) { return solver.solver->kind(); })
      .def_property_readonly("ordering", [](const Solver& solver) { return solver.solver->ordering(); })
      .def_property_readonly("stats", [](const Solver& solver) { return solver.solver->stats(); })
      .def(
          "reset_stats", [](Solver& solver) { solver.solver->resetStats(); }, "sets the statistics back to zero");
}

}  // namespace asyncfem::python
