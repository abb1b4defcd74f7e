// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

namespace asyncfem {

/// A symmetric rank-one term of a force's derivatives that couples up to four vertices
/// (a surface contact pair): with g the 3n vector whose entries at vertex vertices[i] are
/// weights[i] * direction (none where vertices[i] < 0), the term is stiffness g g^T in
/// -df/du and damping g g^T in -df/dv. Its 3 x 3 block between vertices i and j is
/// stiffness w_i w_j N N^T: the off-diagonal blocks a per-vertex list cannot hold.
struct VertexCoupling {
  std::array<int, 4> vertices{-1, -1, -1, -1};
  std::array<double, 4> weights{};
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();
  double stiffness = 0.0;
  double damping = 0.0;
};

/// The derivatives of a force that acts on single vertices (penalty contact), at one
/// state: with the signs of the equation of motion (M a + D v + K u = f),
/// stiffness[k] = -df/du and damping[k] = -df/dv of vertex vertices[k], 3 x 3 blocks in
/// the vertex's (x, y, z) DOFs. A vertex may appear more than once (its blocks add up).
/// couplings: rank-one terms between vertices added to the blocks (empty unless the
/// producer was asked for them: DynamicSystem::externalForceCoupledJacobian).
struct VertexJacobian {
  std::vector<int> vertices;
  std::vector<Eigen::Matrix3d> stiffness;
  std::vector<Eigen::Matrix3d> damping;
  std::vector<VertexCoupling> couplings;

  bool empty() const { return vertices.empty() && couplings.empty(); }
  void clear() {
    vertices.clear();
    stiffness.clear();
    damping.clear();
    couplings.clear();
  }
};

}  // namespace asyncfem
