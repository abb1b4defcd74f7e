// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/SparseCore>
#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <cmath>
#include <utility>
#include <vector>

#include "../common/testProblems.hpp"

// Small bodies with closed-form (modal) solutions shared by the integrator tests.
namespace asyncfem::test {

/// The rubber cantilever of testProblems.hpp (1 x 0.2 x 0.2, 4 x 1 x 1 cubes by default,
/// the x = 0 face fixed: 48 free DOFs, small enough for dense generalized eigen-solves),
/// linear FEM, with its matrices at hand.
struct BarBody : TestBody {
  explicit BarBody(Problem bar)
      : TestBody(std::move(bar)),
        stiffness(this->problem->stiffnessMatrix()),
        mass(this->problem->massMatrix()),
        freeDofs(this->problem->freeDofs()) {}

  const Eigen::SparseMatrix<double>& stiffness;  ///< full K (N/m)
  const Eigen::SparseMatrix<double>& mass;       ///< full M (kg)
  const FreeDofs& freeDofs;
};

/// Rayleigh damping D = alpha M + beta K (alpha in 1/s, beta in s).
inline BarBody makeBar(MassType massType = MassType::consistent, double alpha = 0.0, double beta = 0.0,
                       const Eigen::Vector3i& cells = Eigen::Vector3i(4, 1, 1)) {
  return BarBody(rubberBarProblem(testSettings(ForceModelType::linear, alpha, beta, massType), cells));
}

/// Rows and columns of the free DOFs of a sparse matrix, dense.
inline Eigen::MatrixXd denseFree(const Eigen::SparseMatrix<double>& matrix, const FreeDofs& dofs) {
  const Eigen::MatrixXd dense = Eigen::MatrixXd(matrix);
  const std::vector<int>& free = dofs.freeToFull();
  const auto n = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd out(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j) out(i, j) = dense(free[i], free[j]);
  }
  return out;
}

/// Exact free vibration of the undamped linear system M u'' + K u = 0 on the free DOFs:
/// with K phi = lambda M phi (phi M-orthonormal) every modal coordinate q_i = phi_i^T M u
/// is q_i(0) cos(omega_i t) + q_i'(0) / omega_i sin(omega_i t).
class ModalReference {
 public:
  ModalReference(const Eigen::MatrixXd& stiffness, const Eigen::MatrixXd& mass) : mass_(mass) {
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> solver(stiffness, mass);
    modes_ = solver.eigenvectors();
    omega_ = solver.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  }
  const Eigen::VectorXd& omega() const { return omega_; }
  const Eigen::MatrixXd& modes() const { return modes_; }

  /// Free displacement at time t from free u0, v0.
  Eigen::VectorXd displacement(const Eigen::VectorXd& u0, const Eigen::VectorXd& v0, double t) const {
    const Eigen::VectorXd q0 = modes_.transpose() * (mass_ * u0);
    const Eigen::VectorXd qd0 = modes_.transpose() * (mass_ * v0);
    Eigen::VectorXd q(q0.size());
    for (Eigen::Index i = 0; i < q.size(); ++i) {
      q[i] = q0[i] * std::cos(omega_[i] * t) + qd0[i] / omega_[i] * std::sin(omega_[i] * t);
    }
    return modes_ * q;
  }

 private:
  Eigen::MatrixXd mass_;
  Eigen::MatrixXd modes_;
  Eigen::VectorXd omega_;
};

/// Least-squares slope of log(error) against log(h).
inline double fittedOrder(const std::vector<double>& timesteps, const std::vector<double>& errors) {
  const auto n = static_cast<double>(timesteps.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < timesteps.size(); ++i) {
    const double x = std::log(timesteps[i]);
    const double y = std::log(errors[i]);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

/// Relative comparison |a - b| <= tol * max(1, |a|, |b|) in the infinity norm.
inline double scaledDifference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const double scale = std::max({1.0, a.lpNorm<Eigen::Infinity>(), b.lpNorm<Eigen::Infinity>()});
  return (a - b).lpNorm<Eigen::Infinity>() / scale;
}

}  // namespace asyncfem::test
