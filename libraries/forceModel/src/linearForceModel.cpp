// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/forceModel/linearForceModel.hpp>
#include <string>

namespace asyncfem {

LinearForceModel::LinearForceModel(Eigen::SparseMatrix<double> stiffness) : stiffness_(std::move(stiffness)) {
  if (stiffness_.rows() != stiffness_.cols()) throw Error("LinearForceModel: stiffness matrix is not square");
  stiffness_.makeCompressed();
}

Eigen::SparseMatrix<double> LinearForceModel::createStiffnessMatrix() const {
  Eigen::SparseMatrix<double> pattern = stiffness_;
  std::fill(pattern.valuePtr(), pattern.valuePtr() + pattern.nonZeros(), 0.0);
  return pattern;
}

void LinearForceModel::internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) {
  if (displacement.size() != stiffness_.cols()) {
    throw Error("LinearForceModel: displacement has size " + std::to_string(displacement.size()) + ", expected " +
                std::to_string(stiffness_.cols()));
  }
  forces.noalias() = stiffness_ * displacement;
}

void LinearForceModel::tangentStiffness(const Eigen::VectorXd& /*displacement*/,
                                        Eigen::SparseMatrix<double>& stiffness) {
  if (stiffness.nonZeros() == stiffness_.nonZeros() && stiffness.rows() == stiffness_.rows() &&
      stiffness.isCompressed()) {
    std::copy(stiffness_.valuePtr(), stiffness_.valuePtr() + stiffness_.nonZeros(), stiffness.valuePtr());
  } else {
    stiffness = stiffness_;
  }
}

double LinearForceModel::elasticEnergy(const Eigen::VectorXd& displacement) {
  return 0.5 * displacement.dot(stiffness_ * displacement);
}

}  // namespace asyncfem
