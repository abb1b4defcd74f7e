// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

namespace asyncfem {

/// The surface primitives of one body or obstacle that contact is computed between:
/// triangles, their unique edges and the vertices they use, all indexing the body's own
/// vertices (so the positions passed to queries are the body's 3 x numVertices positions,
/// deformed or not). Built once; positions change, connectivity does not.
struct CollisionSurface {
  /// 3 x numTriangles vertex ids, counter-clockwise seen from outside (normal (b-a)x(c-a)
  /// points out of the body) for a surface built from a tet mesh.
  Eigen::Matrix3Xi triangles;
  /// 2 x numEdges vertex ids, each edge once, smaller id first, sorted.
  Eigen::Matrix2Xi edges;
  /// Ids of the vertices some triangle uses, ascending.
  std::vector<int> vertices;
  /// Number of vertices of the body (positions have this many columns).
  int numMeshVertices = 0;

  int numTriangles() const { return static_cast<int>(triangles.cols()); }
  int numEdges() const { return static_cast<int>(edges.cols()); }
  int numSurfaceVertices() const { return static_cast<int>(vertices.size()); }
};

/// The boundary surface of a tet mesh: the faces that belong to exactly one element,
/// oriented outward (volumetricMesh's boundaryTriangles), with their edges and vertices.
CollisionSurface boundarySurface(const TetMesh& mesh);

/// A surface from a triangle list (a static obstacle, or any triangle mesh): triangles is
/// 3 x m with vertex ids in [0, numVertices). Throws ValidationError naming the triangle
/// for an id out of range or a triangle that repeats a vertex.
CollisionSurface triangleSurface(const Eigen::Matrix3Xi& triangles, int numVertices);

/// Throws ValidationError unless positions is 3 x surface.numMeshVertices with finite
/// entries (naming the first non-finite vertex); `what` starts the message.
void checkPositions(const CollisionSurface& surface, const Eigen::Matrix3Xd& positions, const char* what);

}  // namespace asyncfem
