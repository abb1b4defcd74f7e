// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Dense>
#include <asyncfem/modalAnalysis/generalizedEigen.hpp>

namespace asyncfem {

bool solveGeneralizedEigen(Eigen::MatrixXd& stiffness, Eigen::MatrixXd& mass, Eigen::VectorXd& eigenvalues) {
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> solver(stiffness, mass,
                                                                   Eigen::ComputeEigenvectors | Eigen::Ax_lBx);
  if (solver.info() != Eigen::Success) return false;
  eigenvalues = solver.eigenvalues();
  stiffness = solver.eigenvectors();
  return true;
}

std::string generalizedEigenBackend() { return "Eigen GeneralizedSelfAdjointEigenSolver"; }

}  // namespace asyncfem
