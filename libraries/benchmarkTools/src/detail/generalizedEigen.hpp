// SPDX-License-Identifier: BSD-3-Clause
// Dense symmetric-definite generalized eigenproblem behind ModalReference: LAPACK's
// divide-and-conquer dsygvd when the build found LAPACK, else Eigen (about 20x slower).
#pragma once

#include <Eigen/Core>
#include <string>

namespace asyncfem::detail {

/// Solves K phi = lambda M phi (K symmetric, M symmetric positive definite, n x n dense).
/// On return stiffness holds the M-orthonormal eigenvectors (columns) and eigenvalues the
/// eigenvalues in ascending order. mass is overwritten (its Cholesky factor). Returns false
/// when the solver fails (M not positive definite, no convergence).
bool solveGeneralizedEigen(Eigen::MatrixXd& stiffness, Eigen::MatrixXd& mass, Eigen::VectorXd& eigenvalues);

/// "LAPACK dsygvd" or "Eigen GeneralizedSelfAdjointEigenSolver", for reports.
std::string generalizedEigenBackend();

}  // namespace asyncfem::detail
