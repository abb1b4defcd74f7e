// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/collision/collisionSurface.hpp>
#include <utility>
#include <vector>

namespace asyncfem {

/// How overlapping boxes are found (docs/collision.md, "Broad phase").
/// - DynamicTree: Bullet's dynamic AABB tree (btDbvt, double-precision build), one tree per
///   box set, traversed tree against tree;
/// - SpatialHash: a uniform grid of cells about one box wide, stored as sorted (cell, box)
///   lists that are merged cell by cell;
/// - BruteForce: every pair (for tests and as the benchmarks' baseline).
enum class BroadPhaseMethod { DynamicTree, SpatialHash, BruteForce };

/// The default method: the faster one in the measurements of docs/collision.md.
constexpr BroadPhaseMethod kDefaultBroadPhase = BroadPhaseMethod::SpatialHash;

/// Closed axis-aligned boxes: min and max corners, 3 x numBoxes each (length).
struct BoxSet {
  Eigen::Matrix3Xd min;
  Eigen::Matrix3Xd max;
  int size() const { return static_cast<int>(min.cols()); }
};

/// Every pair (i, j) of a box i of `first` and a box j of `second` that overlap (closed
/// boxes: touching counts), sorted. Throws ValidationError when min and max differ in size,
/// or a box has a non-finite corner or min > max (naming the box).
std::vector<std::pair<int, int>> overlappingBoxes(const BoxSet& first, const BoxSet& second,
                                                  BroadPhaseMethod method = kDefaultBroadPhase);
/// Every pair i < j of overlapping boxes of one set, sorted.
std::vector<std::pair<int, int>> overlappingBoxes(const BoxSet& boxes, BroadPhaseMethod method = kDefaultBroadPhase);

/// A vertex of one surface near a triangle of the other (or the same) surface: the
/// vertex's id in its mesh, the triangle's index in its surface.
struct VertexTriangleCandidate {
  int vertex = -1;
  int triangle = -1;
  bool operator==(const VertexTriangleCandidate&) const = default;
  auto operator<=>(const VertexTriangleCandidate&) const = default;
};

/// Two edges near each other: indices into the edges of the first and second surface.
struct EdgeEdgeCandidate {
  int first = -1;
  int second = -1;
  bool operator==(const EdgeEdgeCandidate&) const = default;
  auto operator<=>(const EdgeEdgeCandidate&) const = default;
};

/// The primitive pairs whose distance may be below dhat: every pair whose boxes, each grown
/// by dhat / 2 on every side, overlap. A pair at distance d < dhat is always among them
/// (distance d means a gap of at most d along every axis); pairs farther apart may be.
/// Each list is sorted.
struct ContactCandidates {
  /// Vertices of the first surface against triangles of the second.
  std::vector<VertexTriangleCandidate> firstVerticesSecondTriangles;
  /// Vertices of the second surface against triangles of the first (empty for self-contact,
  /// where the list above holds every vertex-triangle pair).
  std::vector<VertexTriangleCandidate> secondVerticesFirstTriangles;
  /// Edges of the first surface against edges of the second (self-contact: first < second).
  std::vector<EdgeEdgeCandidate> edgeEdge;

  std::size_t size() const {
    return firstVerticesSecondTriangles.size() + secondVerticesFirstTriangles.size() + edgeEdge.size();
  }
};

/// Candidates between two different surfaces, e.g. a body (first) and a static triangle-mesh
/// obstacle or another body (second), at positions 3 x numMeshVertices of each (length).
/// dhat >= 0 (length). Throws ValidationError for a negative or non-finite dhat or
/// positions of the wrong size or with a non-finite surface vertex.
ContactCandidates findContactCandidates(const CollisionSurface& first, const Eigen::Matrix3Xd& firstPositions,
                                        const CollisionSurface& second, const Eigen::Matrix3Xd& secondPositions,
                                        double dhat, BroadPhaseMethod method = kDefaultBroadPhase);

/// Self-contact candidates of one surface: vertex-triangle pairs except a vertex against the
/// triangles that contain it, edge-edge pairs (first < second) except edges that share a
/// vertex (neighbours are always within any dhat of each other).
ContactCandidates findSelfContactCandidates(const CollisionSurface& surface, const Eigen::Matrix3Xd& positions,
                                            double dhat, BroadPhaseMethod method = kDefaultBroadPhase);

/// Boxes of the surface's vertices (in surface.vertices order), edges and triangles at
/// positions (3 x numMeshVertices), each grown by `margin` (length) on every side.
BoxSet vertexBoxes(const CollisionSurface& surface, const Eigen::Matrix3Xd& positions, double margin);
BoxSet edgeBoxes(const CollisionSurface& surface, const Eigen::Matrix3Xd& positions, double margin);
BoxSet triangleBoxes(const CollisionSurface& surface, const Eigen::Matrix3Xd& positions, double margin);

}  // namespace asyncfem
