// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <vector>

namespace asyncfem {

/// The derivatives of a force that acts on single vertices (penalty contact), at one
/// state: with the signs of the equation of motion (M a + D v + K u = f),
/// stiffness[k] = -df/du and damping[k] = -df/dv of vertex vertices[k], 3 x 3 blocks in
/// the vertex's (x, y, z) DOFs. A vertex may appear more than once (its blocks add up).
struct VertexJacobian {
  std::vector<int> vertices;
  std::vector<Eigen::Matrix3d> stiffness;
  std::vector<Eigen::Matrix3d> damping;

  bool empty() const { return vertices.empty(); }
  void clear() {
    vertices.clear();
    stiffness.clear();
    damping.clear();
  }
};

}  // namespace asyncfem
