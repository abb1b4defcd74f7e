// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <filesystem>
#include <string>
#include <vector>

namespace asyncfem {

/// A triangle soup or mesh with named parts: vertices 3 x n, triangles 3 x m (0-based,
/// counter-clockwise seen from outside for a closed surface), and for every triangle the
/// index of its part in partNames (assimp mesh or node names; one part "surface" if the
/// source has none).
struct TriangleSurface {
  Eigen::Matrix3Xd vertices;
  Eigen::Matrix3Xi triangles;
  std::vector<int> triangleParts;
  std::vector<std::string> partNames;
  /// Optional labels of every triangle (empty when the source has none): its material
  /// (index into materialNames, the file's material names) and its named group (index into
  /// groupNames: the OBJ `g`/`o` group or glTF/FBX node holding it).
  std::vector<int> triangleMaterials;
  std::vector<std::string> materialNames;
  std::vector<int> triangleGroups;
  std::vector<std::string> groupNames;
  /// Optional: each triangle's index in the source file (kept through weldVertices and
  /// selectTriangles, so that messages can name the input's triangle).
  std::vector<int> inputTriangles;

  int numVertices() const { return static_cast<int>(vertices.cols()); }
  int numTriangles() const { return static_cast<int>(triangles.cols()); }
  Eigen::AlignedBox3d bounds() const;
};

/// Merges vertices closer than tolerance (absolute length) into one, keeping the first
/// of each cluster in input order, and drops triangles that become degenerate (two equal
/// corners). Files exported with split normals or texture seams need this before their
/// edges can be matched. Returns the number of vertices removed.
int weldVertices(TriangleSurface& surface, double tolerance);

/// Keeps the triangles listed (in that order), with their parts, labels and input indices.
void selectTriangles(TriangleSurface& surface, const std::vector<int>& keep);

/// The source file's index of triangle t (t itself when inputTriangles is empty).
int inputTriangleIndex(const TriangleSurface& surface, int t);

/// Edge topology of a welded surface.
struct SurfaceTopology {
  int boundaryEdges = 0;        ///< edges in exactly one triangle (holes)
  int nonManifoldEdges = 0;     ///< edges in three or more triangles
  int misorientedEdges = 0;     ///< edges in two triangles that traverse it the same way
  int degenerateTriangles = 0;  ///< zero-area triangles
  /// One example of the first kind found above, for messages: "edge (x, y, z) - (x, y, z)".
  std::string example;
  double signedVolume = 0.0;  ///< divergence-theorem volume (negative: normals point in)
  bool closed() const { return boundaryEdges == 0 && nonManifoldEdges == 0 && misorientedEdges == 0; }
};
SurfaceTopology surfaceTopology(const TriangleSurface& surface);

/// Throws a ValidationError (starting with `source`) unless the surface is closed,
/// manifold and consistently oriented, naming the counts of open, non-manifold and
/// inconsistently oriented edges and one example edge's vertex positions, and pointing to
/// the winding-number fallback (SignMode::WindingNumber, tetMesher --repair).
void requireClosedSurface(const TriangleSurface& surface, const std::string& source);

/// Reverses every triangle (used when a closed surface encloses negative volume).
void flipOrientation(TriangleSurface& surface);

/// Reads every triangle of a file assimp can read (OBJ, STL, PLY, OFF, glTF, FBX, ...),
/// applying node transforms. Each assimp mesh becomes a part named after the mesh, or
/// after its node when the mesh has no name. Polygons are triangulated; points and
/// lines are ignored. Vertices are not welded (call weldVertices). Error if the file
/// cannot be read or holds no triangle, or if this build has no assimp
/// (ASYNCFEM_WITH_ASSIMP=OFF; see surfaceReaderAvailable).
TriangleSurface readSurface(const std::filesystem::path& path);

/// Whether readSurface is compiled in (the build found assimp).
bool surfaceReaderAvailable();

}  // namespace asyncfem
