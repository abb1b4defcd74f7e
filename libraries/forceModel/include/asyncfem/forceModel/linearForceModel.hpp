// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/SparseCore>
#include <asyncfem/forceModel/forceModel.hpp>

namespace asyncfem {

/// Linear FEM: f_int(u) = K u, K constant, energy u^T K u / 2.
class LinearForceModel final : public ForceModel {
 public:
  /// stiffness: 3n x 3n, full storage (e.g. linearStiffnessMatrix()).
  explicit LinearForceModel(Eigen::SparseMatrix<double> stiffness);

  int numDofs() const override { return static_cast<int>(stiffness_.rows()); }
  bool isLinear() const override { return true; }
  Eigen::SparseMatrix<double> createStiffnessMatrix() const override;
  void internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) override;
  void tangentStiffness(const Eigen::VectorXd& displacement, Eigen::SparseMatrix<double>& stiffness) override;
  double elasticEnergy(const Eigen::VectorXd& displacement) override;

  const Eigen::SparseMatrix<double>& stiffness() const { return stiffness_; }

 private:
  Eigen::SparseMatrix<double> stiffness_;
};

}  // namespace asyncfem
