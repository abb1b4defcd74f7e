// SPDX-License-Identifier: BSD-3-Clause
// The dense symmetric-definite generalized eigenproblem K phi = lambda M phi: LAPACK's
// divide-and-conquer dsygvd when the build found LAPACK, else Eigen (about 4x slower at
// n = 1000, 20x on larger problems). Used for a modal reference solution
// (benchmarkTools::ModalReference) and for a small fast region's modes (asyncIntegrator).
#pragma once

#include <Eigen/Core>
#include <string>

namespace asyncfem {

/// Solves K phi = lambda M phi (K symmetric, M symmetric positive definite, n x n dense).
/// On return stiffness holds the M-orthonormal eigenvectors (columns) and eigenvalues the
/// eigenvalues in ascending order. mass is overwritten (its Cholesky factor). Returns false
/// when the solver fails (M not positive definite, no convergence). The result does not
/// depend on the machine's thread count or load (LAPACK runs on one BLAS thread).
bool solveGeneralizedEigen(Eigen::MatrixXd& stiffness, Eigen::MatrixXd& mass, Eigen::VectorXd& eigenvalues);

/// "LAPACK dsygvd" or "Eigen GeneralizedSelfAdjointEigenSolver", for reports.
std::string generalizedEigenBackend();

}  // namespace asyncfem
