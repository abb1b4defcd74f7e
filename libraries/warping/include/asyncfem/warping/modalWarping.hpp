// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <asyncfem/warping/warping.hpp>

namespace asyncfem {

/// Modal warping (Choi & Ko 2005), applied to a full displacement field.
///
/// Per vertex i the local rotation vector (radians) is half the curl of the linear
/// displacement, w_i = (1/2) curl u (X_i). With linear tetrahedra the curl is constant per
/// element, (1/2) curl u |_e = (1/2) sum_a grad N_a x u_a; with trilinear hexahedra the same
/// sum over the eight vertices takes the gradients at the element's centre (exact for affine
/// fields). The vertex value is the volume-weighted mean over the elements around the vertex:
///     w_i = sum_{e ∋ i} V_e (1/2) sum_a grad N_a x u_a  /  sum_{e ∋ i} V_e,
/// a fixed sparse linear map w = C u (3n x 3n) built by the constructor.
///
/// The warped displacement assumes that the rotation grew linearly from 0 to w_i while
/// the local displacement accumulated (Choi & Ko's integration of the rotating frame),
///     u~_i = (1/theta) int_0^theta R(phi a) dphi u_i
///          = u_i + c1(theta) w_i x u_i + c2(theta) w_i x (w_i x u_i),
/// with theta = |w_i|, a = w_i / theta, R(phi a) the rotation by phi about a, and
///     c1 = (1 - cos theta) / theta^2,   c2 = (theta - sin theta) / theta^3
/// (Taylor series 1/2 - theta^2/24 + theta^4/720 - theta^6/40320 and
/// 1/6 - theta^2/120 + theta^4/5040 - theta^6/362880 below theta = 0.05, where the closed
/// forms lose digits to cancellation).
///
/// Properties (tests/warping): u = 0 gives 0 exactly, u_i = 0 (fixed vertices) stays 0, a
/// translation stays that translation (to rounding), and the linearised rigid rotation
/// u = theta [a]x (X - c) maps exactly to the rigid rotation (R(theta a) - I)(X - c),
/// because int_0^theta R(phi a) [a]x dphi = R(theta a) - I. Cheaper than
/// RotationStrainWarping (one sparse product, no solve) but only exact for rigid motion:
/// rotations that vary over the mesh leave some distortion.
class ModalWarping final : public Warping {
 public:
  /// mesh: every element must have non-zero volume (asyncfem::ValidationError naming the
  /// first degenerate one).
  explicit ModalWarping(const TetMesh& mesh);

  WarpingKind kind() const override { return WarpingKind::modal; }
  int numVertices() const override { return numVertices_; }
  /// Warped displacement (3n) for a linear displacement (3n); see the class comment.
  Eigen::VectorXd warp(const Eigen::Ref<const Eigen::VectorXd>& displacement) override;

  /// Per-vertex rotation vectors w = C u (3n, radians) of a displacement (3n).
  Eigen::VectorXd rotationVectors(const Eigen::Ref<const Eigen::VectorXd>& displacement) const;
  /// The map C (3n x 3n, units 1 / length).
  const Eigen::SparseMatrix<double, Eigen::RowMajor>& curlOperator() const { return curl_; }

 private:
  int numVertices_ = 0;
  Eigen::SparseMatrix<double, Eigen::RowMajor> curl_;
};

}  // namespace asyncfem
