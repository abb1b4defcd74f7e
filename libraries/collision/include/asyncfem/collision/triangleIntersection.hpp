// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/collision/broadPhase.hpp>
#include <asyncfem/collision/collisionSurface.hpp>
#include <utility>
#include <vector>

namespace asyncfem {

/// Whether the closed triangles (a0, a1, a2) and (b0, b1, b2) share a point: crossing,
/// touching at a vertex or along an edge, and overlapping coplanar triangles all count.
/// Exact (orientation signs with exact arithmetic where floating point cannot decide;
/// finite coordinates whose products neither overflow nor underflow), for degenerate
/// (zero-area) triangles too. Two triangles meet iff an edge of one meets the other.
bool trianglesIntersect(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& a2,
                        const Eigen::Vector3d& b0, const Eigen::Vector3d& b1, const Eigen::Vector3d& b2);

/// Pairs (triangle of first, triangle of second) that intersect, at positions
/// 3 x numMeshVertices of each, sorted: the check that two bodies, or a body and an
/// obstacle, do not interpenetrate at a frame (surfaces resting in contact touch, and touch
/// counts). Throws ValidationError for positions of the wrong size or not finite.
std::vector<std::pair<int, int>> intersectingTrianglePairs(const CollisionSurface& first,
                                                           const Eigen::Matrix3Xd& firstPositions,
                                                           const CollisionSurface& second,
                                                           const Eigen::Matrix3Xd& secondPositions,
                                                           BroadPhaseMethod method = kDefaultBroadPhase);

/// Pairs (i < j) of triangles of one surface that intersect and share no vertex (triangles
/// sharing a vertex always touch there; a fold through such a neighbour is not reported).
std::vector<std::pair<int, int>> selfIntersectingTrianglePairs(const CollisionSurface& surface,
                                                               const Eigen::Matrix3Xd& positions,
                                                               BroadPhaseMethod method = kDefaultBroadPhase);

}  // namespace asyncfem
