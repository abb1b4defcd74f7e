// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/tetMesher/implicit.hpp>
#include <asyncfem/tetMesher/triangleSurface.hpp>
#include <memory>
#include <vector>

namespace asyncfem {

/// How SignedDistance decides inside from outside.
enum class SignMode {
  /// Sign of (x - closest point) . n, with n the angle-weighted pseudonormal of the closest
  /// feature (face, edge or vertex; Baerentzen & Aanaes 2005). Exact for closed, manifold,
  /// consistently oriented surfaces; costs one closest-point query.
  Pseudonormal,
  /// Inside where the generalized winding number w(x) = (1/4pi) sum of the triangles'
  /// signed solid angles exceeds 1/2 (Jacobson, Kavan & Sorkine-Hornung 2013); tolerates
  /// small holes, overlaps and stray triangles. Far clusters of triangles are summed as
  /// one dipole (first-order far field, as in Barill et al. 2018) when the query point is
  /// more than farFieldRatio times the cluster's radius away.
  WindingNumber,
};

/// Signed distance to a triangle surface: negative inside, positive outside, magnitude the
/// Euclidean distance to the nearest triangle. A bounding-volume hierarchy over the
/// triangles (median splits along the longest axis, leaves of up to 4) answers closest-point
/// queries in about O(log m). Safe to call from several threads at once.
class SignedDistance {
 public:
  /// The surface is copied. ValidationError for a surface without triangles.
  explicit SignedDistance(TriangleSurface surface, SignMode mode = SignMode::Pseudonormal, double farFieldRatio = 2.0);
  ~SignedDistance();
  SignedDistance(SignedDistance&&) noexcept;
  SignedDistance& operator=(SignedDistance&&) noexcept;

  /// Signed distance at x (length units of the surface).
  double operator()(const Eigen::Vector3d& x) const;
  /// Unsigned distance at x and the index of the nearest triangle.
  double distance(const Eigen::Vector3d& x, int* nearestTriangle = nullptr) const;
  /// Generalized winding number at x (1 inside a closed outward surface, 0 outside).
  double windingNumber(const Eigen::Vector3d& x) const;

  const TriangleSurface& surface() const;
  SignMode mode() const;

  /// A copyable ImplicitFunction that shares this object's data structures: it stays valid
  /// while this object (or the one it is moved into) lives.
  ImplicitFunction function() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace asyncfem
