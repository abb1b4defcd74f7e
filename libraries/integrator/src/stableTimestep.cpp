// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/stableTimestep.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <cmath>
#include <string>

#include "detail/freeSystem.hpp"

namespace asyncfem {

double estimateMaxFrequency(const TetMesh& mesh, MassType massType) {
  double largest = 0.0;
  for (int e = 0; e < mesh.numElements(); ++e) {
    const ElementPositions rest = mesh.elementRestPositions(e);
    double signedVolume = 0.0;
    shapeFunctionGradients(rest, &signedVolume);
    if (!(signedVolume > 0.0)) {
      throw ValidationError("element " + std::to_string(e) + " has non-positive volume " +
                            std::to_string(signedVolume) + "; cannot estimate the stable timestep");
    }
    const Material& material = mesh.elementMaterial(e);
    const ElementMatrix stiffness = linearElementStiffness(rest, material.youngsModulus, material.poissonRatio);
    double lambda = 0.0;
    if (massType == MassType::lumped) {
      // M_e = m I: lambda_max(K_e, M_e) = lambda_max(K_e) / m.
      const double nodalMass = material.density * signedVolume / 4.0;
      Eigen::SelfAdjointEigenSolver<ElementMatrix> solver(stiffness, Eigen::EigenvaluesOnly);
      lambda = solver.eigenvalues().maxCoeff() / nodalMass;
    } else {
      const ElementMatrix mass = consistentElementMass(signedVolume, material.density);
      Eigen::GeneralizedSelfAdjointEigenSolver<ElementMatrix> solver(stiffness, mass, Eigen::EigenvaluesOnly);
      lambda = solver.eigenvalues().maxCoeff();
    }
    largest = std::max(largest, lambda);
  }
  return std::sqrt(largest);
}

double estimateMaxFrequency(const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass) {
  const Eigen::Index n = stiffness.rows();
  if (n == 0) return 0.0;
  if (detail::isDiagonal(mass)) {
    Eigen::VectorXd rowSums = Eigen::VectorXd::Zero(n);
    for (int col = 0; col < stiffness.outerSize(); ++col) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(stiffness, col); it; ++it) {
        rowSums[it.row()] += std::abs(it.value());
      }
    }
    const Eigen::VectorXd diagonal = mass.diagonal();
    double largest = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) largest = std::max(largest, rowSums[i] / diagonal[i]);
    return std::sqrt(largest);
  }
  std::unique_ptr<SparseSolver> solver = makeSparseSolver(SolverKind::cholmod);
  solver->compute(mass);
  Eigen::VectorXd x(n);
  // A deterministic start vector with components along every mode.
  for (Eigen::Index i = 0; i < n; ++i) x[i] = std::sin(0.7 * static_cast<double>(i) + 0.3) + 0.1;
  double rayleigh = 0.0;
  Eigen::MatrixXd y;
  for (int iteration = 0; iteration < 500; ++iteration) {
    const Eigen::VectorXd kx = stiffness * x;
    const double quotient = x.dot(kx) / x.dot(mass * x);
    solver->solve(kx, y);
    x = y.col(0) / y.col(0).norm();
    const bool converged = iteration > 10 && std::abs(quotient - rayleigh) <= 1e-6 * quotient;
    rayleigh = quotient;
    if (converged) break;
  }
  return std::sqrt(1.1 * rayleigh);
}

}  // namespace asyncfem
