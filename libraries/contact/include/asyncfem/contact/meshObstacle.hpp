// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

namespace asyncfem {

/// A rigid placement at a time: x -> rotation x + translation.
struct RigidKey {
  double time = 0.0;  ///< seconds
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
};

/// A prescribed rigid motion through keyframes: between keys k and k+1 the translation moves
/// linearly and the rotation turns at a constant rate about one axis (the shorter arc from
/// key k's rotation to key k+1's, i.e. spherical linear interpolation); before the first key
/// and after the last the placement is held.
class RigidPath {
 public:
  /// Throws ValidationError for fewer than two keys, times that do not increase strictly,
  /// or a non-finite entry (naming the key).
  explicit RigidPath(std::vector<RigidKey> keys);

  /// The placement at time t: rotation R (3 x 3) and translation T, with the angular
  /// velocity omega and the velocity of the origin Tdot (so a point x of the obstacle moves
  /// at omega x (R x) + Tdot). Between keys the velocities are those of the segment; at a key
  /// and outside the keys' span, those of the segment the time falls in (zero outside).
  void placement(double t, Eigen::Matrix3d& rotation, Eigen::Vector3d& translation, Eigen::Vector3d& angularVelocity,
                 Eigen::Vector3d& velocity) const;

  const std::vector<RigidKey>& keys() const { return keys_; }

 private:
  std::vector<RigidKey> keys_;
};

/// A triangle-mesh obstacle: vertices 3 x m in its own frame (any static placement already
/// applied), triangles 3 x t (0-based). With a path, its vertices are at R(t) x + T(t).
/// closed: the surface is closed and its triangles face outward, so a body vertex behind a
/// face (within the contact thickness) is inside the obstacle and is pushed back out;
/// otherwise both sides of the surface repel.
struct MeshObstacle {
  std::string name;
  Eigen::Matrix3Xd vertices;
  Eigen::Matrix3Xi triangles;
  bool closed = true;
  std::optional<RigidPath> path;
};

}  // namespace asyncfem
