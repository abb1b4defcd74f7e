// SPDX-License-Identifier: BSD-3-Clause
// Rotations of a body's vertices since a reference state, for the lagged Schur factor's
// preconditioner (docs/asynchronous-integrator.md, "The lagged factor turned with the
// body"). In the public include tree for its unit test only; not part of the API.
#pragma once

#include <Eigen/Core>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

namespace asyncfem::detail {

/// For every vertex, the rotation R_v of the polar decomposition of the mean deformation
/// gradient of its elements, measured from a reference state (not from rest): F_e = D_e
/// D_e,ref^{-1} with D the element's edge matrix (on a hexahedron its three edges at vertex
/// 0, exact for an affine motion such as a turn). A corotational or hyperelastic tangent
/// that has only turned with the body since the reference satisfies K ~ R K_ref R^T, with R
/// the block diagonal of the R_v, and so does the Schur system of the large step; rotate()
/// applies R or R^T to a vector on a list of DOFs.
class VertexRotations {
 public:
  /// The reference state (e.g. where the lagged factor was built); every rotation becomes
  /// the identity. Elements flat or inverted there (|det D| below 1e-8 of its rest value)
  /// are left out of the means.
  void setReference(const TetMesh& mesh, const Eigen::VectorXd& displacement);
  /// The rotations at displacement (3n) since the reference; each starts Newton's method
  /// from the last one. A vertex whose elements were all left out, or whose mean gradient
  /// is not finite, keeps the identity.
  void update(const TetMesh& mesh, const Eigen::VectorXd& displacement);
  /// x <- R x (transpose: R^T x), where x lives on dofs (global DOF ids, ascending): every
  /// vertex whose three DOFs are consecutive entries of dofs is turned; the other entries
  /// are left as they are.
  void rotate(const std::vector<int>& dofs, Eigen::VectorXd& x, bool transpose) const;
  /// block <- R block R^T for a square block on dofs (as rotate()).
  void turnBlock(const std::vector<int>& dofs, Eigen::MatrixXd& block) const;
  /// Largest rotation angle (radians) over the vertices at the last update().
  double largestAngle() const { return largestAngle_; }
  bool empty() const { return rotations_.empty(); }

 private:
  /// visit(position in dofs, R_v) for every vertex whose three DOFs are consecutive in dofs.
  template <class Visit>
  void forEachTurnedVertex(const std::vector<int>& dofs, Visit&& visit) const;

  std::vector<Eigen::Matrix3d> referenceInverse_;  // per element: D_ref^{-1}, zero when left out
  std::vector<Eigen::Matrix3d> rotations_;         // per vertex
  std::vector<Eigen::Matrix3d> meanGradient_;      // per vertex, scratch
  double largestAngle_ = 0.0;
};

}  // namespace asyncfem::detail
