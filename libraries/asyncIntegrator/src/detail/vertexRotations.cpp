// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <asyncfem/asyncIntegrator/detail/vertexRotations.hpp>
#include <asyncfem/corotationalLinearFEM/polarDecomposition.hpp>
#include <cmath>

namespace asyncfem::detail {

namespace {
/// Below this fraction of its rest value, an element's |det D| counts as flat.
constexpr double kFlatElement = 1e-8;

/// The element's edge matrix at displacement (null: at rest): the edges from vertex 0 to
/// vertices 1, 2, 3 of a tetrahedron, to its three neighbours 1, 3, 4 on a hexahedron.
Eigen::Matrix3d edgeMatrix(const TetMesh& mesh, const Eigen::VectorXd* displacement, int element) {
  static constexpr std::array<int, 4> kTetCorners{0, 1, 2, 3}, kHexCorners{0, 1, 3, 4};
  const std::array<int, 4>& corners = mesh.isHexahedral() ? kHexCorners : kTetCorners;
  const auto corner = [&](int c) -> Eigen::Vector3d {
    const int v = mesh.elementVertex(element, corners[static_cast<std::size_t>(c)]);
    const Eigen::Vector3d rest = mesh.restPosition(v);
    return displacement ? Eigen::Vector3d(rest + displacement->segment<3>(3 * static_cast<Eigen::Index>(v))) : rest;
  };
  const Eigen::Vector3d x0 = corner(0);
  Eigen::Matrix3d d;
  for (int c = 1; c < 4; ++c) d.col(c - 1) = corner(c) - x0;
  return d;
}
}  // namespace

void VertexRotations::setReference(const TetMesh& mesh, const Eigen::VectorXd& displacement) {
  const int elements = mesh.numElements();
  referenceInverse_.resize(static_cast<std::size_t>(elements));
  for (int e = 0; e < elements; ++e) {
    const Eigen::Matrix3d d = edgeMatrix(mesh, &displacement, e);
    const double restDeterminant = std::abs(edgeMatrix(mesh, nullptr, e).determinant());
    const double determinant = d.determinant();
    referenceInverse_[static_cast<std::size_t>(e)] =
        std::abs(determinant) > kFlatElement * restDeterminant && std::isfinite(determinant)
            ? Eigen::Matrix3d(d.inverse())
            : Eigen::Matrix3d::Zero();
  }
  rotations_.assign(static_cast<std::size_t>(mesh.numVertices()), Eigen::Matrix3d::Identity());
  largestAngle_ = 0.0;
}

void VertexRotations::update(const TetMesh& mesh, const Eigen::VectorXd& displacement) {
  meanGradient_.assign(rotations_.size(), Eigen::Matrix3d::Zero());
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Eigen::Matrix3d& inverse = referenceInverse_[static_cast<std::size_t>(e)];
    if (inverse.isZero(0.0)) continue;
    const Eigen::Matrix3d gradient = edgeMatrix(mesh, &displacement, e) * inverse;
    for (int c = 0; c < mesh.verticesPerElement(); ++c)
      meanGradient_[static_cast<std::size_t>(mesh.elementVertex(e, c))] += gradient;
  }
  largestAngle_ = 0.0;
  for (std::size_t v = 0; v < rotations_.size(); ++v) {
    const Eigen::Matrix3d& gradient = meanGradient_[v];
    if (gradient.isZero(0.0) || !gradient.allFinite()) {
      rotations_[v].setIdentity();
      continue;
    }
    const Eigen::Matrix3d last = rotations_[v];
    rotations_[v] = polarRotation(gradient, &last).rotation;
    const double cosine = std::clamp(0.5 * (rotations_[v].trace() - 1.0), -1.0, 1.0);
    largestAngle_ = std::max(largestAngle_, std::acos(cosine));
  }
}

template <class Visit>
void VertexRotations::forEachTurnedVertex(const std::vector<int>& dofs, Visit&& visit) const {
  std::size_t k = 0;
  while (k + 2 < dofs.size()) {
    const int dof = dofs[k];
    if (dof % 3 != 0 || dofs[k + 1] != dof + 1 || dofs[k + 2] != dof + 2) {
      ++k;
      continue;
    }
    visit(static_cast<Eigen::Index>(k), rotations_[static_cast<std::size_t>(dof / 3)]);
    k += 3;
  }
}

void VertexRotations::rotate(const std::vector<int>& dofs, Eigen::VectorXd& x, bool transpose) const {
  forEachTurnedVertex(dofs, [&](Eigen::Index at, const Eigen::Matrix3d& rotation) {
    const Eigen::Vector3d y = x.segment<3>(at);
    x.segment<3>(at) = transpose ? Eigen::Vector3d(rotation.transpose() * y) : Eigen::Vector3d(rotation * y);
  });
}

void VertexRotations::turnBlock(const std::vector<int>& dofs, Eigen::MatrixXd& block) const {
  // R block: every row triple of a turned vertex; then (R block) R^T: every column triple.
  forEachTurnedVertex(dofs, [&](Eigen::Index at, const Eigen::Matrix3d& rotation) {
    block.middleRows<3>(at) = (rotation * block.middleRows<3>(at)).eval();
  });
  forEachTurnedVertex(dofs, [&](Eigen::Index at, const Eigen::Matrix3d& rotation) {
    block.middleCols<3>(at) = (block.middleCols<3>(at) * rotation.transpose()).eval();
  });
}

}  // namespace asyncfem::detail
