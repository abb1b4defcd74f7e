// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <string>

namespace asyncfem {

/// Dihedral-angle summary of a whole mesh, in degrees.
struct MeshQuality {
  double minDihedralDegrees = 0.0;  ///< smallest dihedral angle of any element
  double maxDihedralDegrees = 0.0;  ///< largest dihedral angle of any element
  double worstAspectRatio = 0.0;    ///< largest elementQuality().aspectRatio
};
/// Quality of every element folded into one summary (zeros for an empty mesh).
MeshQuality meshQuality(const TetMesh& mesh);

/// Everything validateTetMesh checks, counted.
struct MeshCheckReport {
  int invertedElements = 0;    ///< signed volume < 0
  int degenerateElements = 0;  ///< |volume| <= 1e-10 (mean edge)^3, or min dihedral < 0.01 degrees
  int unusedVertices = 0;
  int boundaryTriangles = 0;
  int openBoundaryEdges = 0;         ///< boundary edges in one boundary triangle
  int nonManifoldBoundaryEdges = 0;  ///< boundary edges in three or more boundary triangles,
                                     ///< not traversed equally often in both directions
  /// Boundary edges in four (or any even number of) boundary triangles, traversed equally
  /// often in both directions: sheets of a closed, outward boundary touching along the edge
  /// (a solid pinched there, such as two parts meeting at an edge). Not a failure.
  int pinchedBoundaryEdges = 0;
  int misorientedBoundaryEdges = 0;  ///< edges whose two boundary triangles run the same way
  int components = 0;                ///< connected components (elements sharing a face)
  double elementVolume = 0.0;        ///< sum of signed element volumes
  double boundaryVolume = 0.0;       ///< sum over boundary triangles of x_a . (x_b x x_c) / 6
  /// First problem found, for messages ("" when every check passes).
  std::string firstProblem;
  bool ok() const { return firstProblem.empty(); }
};

/// Checks that the mesh is usable: no inverted or degenerate element, every vertex used,
/// the boundary surface closed and consistently oriented (every boundary edge traversed
/// equally often in each direction: once each way, or in pinches several times), and the volume
/// enclosed by the outward boundary (divergence theorem) equal to the element volume to a
/// relative 1e-9. Counts connected components but does not require one.
MeshCheckReport checkTetMesh(const TetMesh& mesh);

/// checkTetMesh, throwing a ValidationError starting with `context` and naming the first
/// failed check with an example element or edge.
void validateTetMesh(const TetMesh& mesh, const std::string& context);

}  // namespace asyncfem
