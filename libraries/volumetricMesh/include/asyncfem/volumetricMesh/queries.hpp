// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <array>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

namespace asyncfem {

/// Signed volume of element e at rest: det([x1-x0, x2-x0, x3-x0]) / 6 for a tetrahedron,
/// the integral of det J for a hexahedron (hexahedron::signedVolume). Positive for the
/// orientation the toolkit uses.
double signedElementVolume(const TetMesh& mesh, int e);
/// |signed volume| of every element (size numElements).
Eigen::VectorXd elementVolumes(const TetMesh& mesh);
/// Sum of the element volumes.
double totalVolume(const TetMesh& mesh);
/// Sum of rho * V over elements.
double totalMass(const TetMesh& mesh);

/// Boundary triangles: faces that belong to exactly one element, oriented so that
/// their normal (b-a)x(c-a) points out of the mesh. Deterministic order. A hexahedral
/// mesh's boundary quadrilaterals a b c d (outward, hexahedron::kFaces) give the two
/// triangles a b c and a c d each.
std::vector<std::array<int, 3>> boundaryTriangles(const TetMesh& mesh);

/// Vertex -> incident elements in compressed form (offsets has numVertices + 1 entries): the elements of vertex v are
/// elements[offsets[v] .. offsets[v+1]), ascending.
struct VertexElementAdjacency {
  std::vector<int> offsets;
  std::vector<int> elements;
};
/// Builds the vertex -> element adjacency in O(numElements).
VertexElementAdjacency vertexElementAdjacency(const TetMesh& mesh);

/// Axis-aligned box, min and max corner.
struct BoundingBox {
  Eigen::Vector3d min;
  Eigen::Vector3d max;
};
/// Corner i (0 <= i < 8) of box: bit 0 of i takes max.x instead of min.x, bit 1 max.y,
/// bit 2 max.z.
inline Eigen::Vector3d boxCorner(const BoundingBox& box, int i) {
  return {(i & 1) != 0 ? box.max.x() : box.min.x(), (i & 2) != 0 ? box.max.y() : box.min.y(),
          (i & 4) != 0 ? box.max.z() : box.min.z()};
}
/// Box of the rest positions (of positions + displacement if given, size 3n; other sizes
/// throw ValidationError). Zero box for a mesh without vertices.
BoundingBox boundingBox(const TetMesh& mesh, const Eigen::VectorXd& displacement = {});

/// Shape quality of one element.
struct ElementQuality {
  double minDihedralAngle = 0.0;  ///< radians
  double maxDihedralAngle = 0.0;  ///< radians
  /// Longest edge / (2 * sqrt(6) * inradius): 1 for the regular tetrahedron, grows as
  /// the element degenerates.
  double aspectRatio = 0.0;
};
/// Quality of element e of a tetrahedral mesh (ValidationError on hexahedra). Dihedral angle at an edge = angle between
/// the two faces that share it (acos(1/3) for all six edges of the regular tetrahedron); a zero-volume element has
/// aspect ratio +infinity.
ElementQuality elementQuality(const TetMesh& mesh, int e);
/// elementQuality for every element, in element order.
std::vector<ElementQuality> elementQualities(const TetMesh& mesh);

/// The spread of element quality over a mesh: the smallest and the largest dihedral angle
/// of any element, the mean of the elements' smallest dihedral angles, how many elements
/// have a dihedral angle below a threshold, and the worst (largest) aspect ratio. All zero
/// for a mesh without elements.
struct QualitySummary {
  double minDihedralDegrees = 0.0;      ///< smallest dihedral angle of any element
  double maxDihedralDegrees = 0.0;      ///< largest dihedral angle of any element
  double meanMinDihedralDegrees = 0.0;  ///< mean over elements of each element's smallest dihedral angle
  double thresholdDegrees = 0.0;        ///< the threshold elementsBelowThreshold counts against
  int elementsBelowThreshold = 0;       ///< elements whose smallest dihedral angle is below thresholdDegrees
  double worstAspectRatio = 0.0;
};
/// QualitySummary of elementQualities(mesh), counting the elements with a dihedral angle
/// below thresholdDegrees (10 by default: tetMesher's guard, docs/tet-mesher.md).
QualitySummary summarizeQuality(const TetMesh& mesh, double thresholdDegrees = 10.0);

/// Shape quality of one hexahedron.
struct HexahedronQuality {
  /// The smallest scaled Jacobian of the eight corners (hexahedron::cornerScaledJacobians;
  /// 1 for a box, <= 0 where the element is inverted or flat; a zero-length edge counts 0).
  double minScaledJacobian = 0.0;
  int worstCorner = 0;     ///< the corner (0..7) where it is attained
  double edgeRatio = 0.0;  ///< longest / shortest of the 12 edges (1 for a cube)
};
/// Quality of hexahedron e (ValidationError on a tetrahedral mesh or e out of range).
HexahedronQuality hexahedronQuality(const TetMesh& mesh, int e);

/// The spread of hexahedron quality over a mesh; all zero for a mesh without elements.
struct HexahedronQualitySummary {
  double minScaledJacobian = 0.0;      ///< smallest corner scaled Jacobian of any element
  double meanMinScaledJacobian = 0.0;  ///< mean over elements of each element's smallest
  double worstEdgeRatio = 0.0;
  std::vector<int> invertedElements;  ///< elements with a corner scaled Jacobian <= 0, ascending
};
HexahedronQualitySummary summarizeHexahedronQuality(const TetMesh& mesh);

/// Vertices referenced by no element.
std::vector<int> unusedVertices(const TetMesh& mesh);

}  // namespace asyncfem
