// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Eigenvalues>
#include <asyncfem/integrator/contactBlock.hpp>

namespace asyncfem {

namespace {

// The symmetric part of block with its negative eigenvalues set to zero.
Eigen::Matrix3d symmetricPositivePart(const Eigen::Matrix3d& block) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(0.5 * (block + block.transpose()));
  const Eigen::Vector3d clamped = eigen.eigenvalues().cwiseMax(0.0);
  return eigen.eigenvectors() * clamped.asDiagonal() * eigen.eigenvectors().transpose();
}

}  // namespace

Eigen::Matrix3d contactStepBlock(const FreeDofs& dofs, const VertexJacobian& jacobian, std::size_t k,
                                 double stiffnessWeight, double dampingWeight) {
  Eigen::Matrix3d block =
      symmetricPositivePart((stiffnessWeight * jacobian.stiffness[k]) + (dampingWeight * jacobian.damping[k]));
  const std::vector<int>& fullToFree = dofs.fullToFree();
  for (int c = 0; c < 3; ++c) {
    if (fullToFree[static_cast<std::size_t>((3 * jacobian.vertices[k]) + c)] < 0) {
      block.row(c).setZero();
      block.col(c).setZero();
    }
  }
  return block;
}

}  // namespace asyncfem
