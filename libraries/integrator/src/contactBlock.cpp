// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Eigenvalues>
#include <asyncfem/integrator/contactBlock.hpp>
#include <cmath>

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

VertexJacobian boundCouplings(const VertexJacobian& jacobian) {
  VertexJacobian out = jacobian;
  out.couplings.clear();
  for (const VertexCoupling& coupling : jacobian.couplings) {
    double sum = 0.0;
    for (std::size_t i = 0; i < 4; ++i)
      if (coupling.vertices[i] >= 0) sum += std::abs(coupling.weights[i]);
    const Eigen::Matrix3d normalBlock = coupling.direction * coupling.direction.transpose();
    for (std::size_t i = 0; i < 4; ++i) {
      if (coupling.vertices[i] < 0) continue;
      const double scale = std::abs(coupling.weights[i]) * sum;
      out.vertices.push_back(coupling.vertices[i]);
      out.stiffness.push_back(coupling.stiffness * scale * normalBlock);
      out.damping.push_back(coupling.damping * scale * normalBlock);
    }
  }
  return out;
}

}  // namespace asyncfem
