// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/render/surfaceEmbedding.hpp>
#include <asyncfem/render/surfaceMesh.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <filesystem>

namespace asyncfem {

/// The weights of a Vega .interp file (docs/file-formats.md): for each render-mesh vertex
/// k, four tet-mesh vertices (0-based) and their weights (the vertex's barycentric
/// coordinates in the tetrahedron that holds it). The render vertex moves by
/// sum_a weights(a, k) u(vertices(a, k)).
struct VegaInterpolation {
  Eigen::Matrix4Xi vertices;  ///< 4 x m tet-mesh vertex ids
  Eigen::Matrix4Xd weights;   ///< 4 x m weights, each column summing to 1
};

/// How far a column of .interp weights may sum from 1: Vega writes them with six
/// significant digits (%G), four terms, so a sum is off by at most about 2e-6; 1e-4 leaves
/// room for hand-edited files and still rejects weights that would not carry a rigid
/// translation (a render mesh that drifts off the body).
inline constexpr double vegaInterpolationSumTolerance = 1e-4;

/// Reads a Vega .interp file: one line per render vertex, "k v0 w0 v1 w1 v2 w2 v3 w3"
/// with k = 0, 1, ... in order, v_a 0-based tet-mesh vertex ids and w_a finite weights
/// summing to 1 (vegaInterpolationSumTolerance); blank lines and '#' comments are skipped.
/// Throws asyncfem::ParseError "FILE:LINE: ..." for a malformed line, a vertex index out
/// of order, an id outside [0, numTetVertices), a weight that is not finite, weights that
/// do not sum to 1, 8 pairs (Vega's cube meshes: not supported here), and for a line count
/// other than numRenderVertices (line 0).
VegaInterpolation readVegaInterpolation(const std::filesystem::path& path, int numRenderVertices, int numTetVertices);

/// Reads a Wavefront OBJ keeping its vertices in file order and unmerged (Vega's .interp
/// files index them so; loadSurfaceMesh may merge and reorder): `v x y z` and `f` lines
/// (`a`, `a/t`, `a//n`, `a/t/n`, 1-based or negative relative ids, polygons split into a
/// fan of triangles); other lines (vt, vn, g, o, s, usemtl, mtllib, comments) are skipped.
/// Throws asyncfem::ParseError "FILE:LINE: ..." for a malformed v or f line or a face
/// naming a missing vertex, and when the file holds no triangle.
SurfaceMesh readObjInFileOrder(const std::filesystem::path& path);

/// A Vega secondary render mesh (OBJ) embedded in mesh by the weights of its .interp file.
SurfaceEmbedding embedWithVegaInterpolation(const TetMesh& mesh, const std::filesystem::path& renderMesh,
                                            const std::filesystem::path& interpolation);

}  // namespace asyncfem
