// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <array>
#include <asyncfem/render/surfaceMesh.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

namespace asyncfem {

/// A triangle surface that follows a volumetric mesh's displacement: either the mesh's own
/// boundary, or a separate render mesh embedded in it.
///
/// Every surface vertex p stores k mesh vertices v_a and weights w_a (computed once by the
/// factory functions; k = 4, or 8 for a render mesh embedded in hexahedra). The deformed
/// position for a stacked 3n displacement u is
///     x(p) = p + sum_a w_a u(v_a),
/// and per-mesh-vertex attributes (colours) interpolate the same way. For the boundary
/// surface the weights are (1, 0, 0, 0) on the vertex itself, so x = X + u exactly. For
/// an embedded mesh the w_a are the barycentric coordinates of p in the tetrahedron that
/// contains it or, for a vertex outside the tet mesh, in the nearest tetrahedron (then
/// some w_a are negative: the nearest element's affine field is extrapolated, which keeps
/// the surface attached under any affine motion, in particular rigid ones). In a hexahedral
/// mesh they are the eight trilinear shape functions at p's reference coordinates in the
/// containing (or nearest) hexahedron, found by Newton's method
/// (hexahedron::referenceCoordinates); trilinear interpolation reproduces affine motions too.
class SurfaceEmbedding {
 public:
  SurfaceEmbedding() = default;

  /// The boundary triangles of mesh (boundaryTriangles(), outward oriented) over the
  /// vertices they use.
  static SurfaceEmbedding boundary(const TetMesh& mesh);
  /// surface embedded in mesh (same coordinates; tetrahedra or hexahedra). Point location uses a uniform grid over
  /// the element bounding boxes: O((elements + surface vertices) * local density).
  /// Throws asyncfem::ValidationError if mesh has no element or a surface triangle names
  /// a vertex out of range.
  static SurfaceEmbedding embed(const TetMesh& mesh, SurfaceMesh surface);
  /// surface with weights given by the caller (e.g. a Vega .interp file): tetVertices
  /// (4 x m, ids in [0, numTetVertices)) and weights (4 x m) of its m vertices. Throws
  /// asyncfem::ValidationError on a size mismatch, an id out of range or a triangle naming
  /// a vertex out of range; the weights are used as given.
  static SurfaceEmbedding withWeights(int numTetVertices, SurfaceMesh surface, Eigen::Matrix4Xi tetVertices,
                                      Eigen::Matrix4Xd weights);

  int numSurfaceVertices() const { return static_cast<int>(surface_.vertices.cols()); }
  int numTetVertices() const { return numTetVertices_; }
  /// The rest surface (positions at u = 0) and its triangles.
  const SurfaceMesh& restSurface() const { return surface_; }
  const std::vector<std::array<int, 3>>& triangles() const { return surface_.triangles; }
  /// Surface vertices outside every element (extrapolated from the nearest one).
  int numOutsideVertices() const { return numOutside_; }
  /// Largest distance from an outside vertex to its element (0 if none), length units.
  double maxOutsideDistance() const { return maxOutsideDistance_; }

  /// Mesh vertex ids (k x m, k = 4, or 8 when embedded in hexahedra) and weights (k x m) of
  /// the surface vertices.
  const Eigen::MatrixXi& tetVertices() const { return tetVertices_; }
  const Eigen::MatrixXd& weights() const { return weights_; }

  /// Deformed surface positions (3 x m) for a stacked displacement of the tet mesh (3n;
  /// asyncfem::Error otherwise).
  Eigen::Matrix3Xd positions(const Eigen::Ref<const Eigen::VectorXd>& displacement) const;
  /// A per-tet-vertex attribute (3 x n, e.g. RGB colours) at the surface vertices (3 x m),
  /// interpolated with the weights (asyncfem::Error on a size mismatch).
  Eigen::Matrix3Xf interpolate(const Eigen::Matrix3Xf& perTetVertex) const;

 private:
  SurfaceMesh surface_;
  int numTetVertices_ = 0;
  Eigen::MatrixXi tetVertices_;
  Eigen::MatrixXd weights_;
  int numOutside_ = 0;
  double maxOutsideDistance_ = 0.0;
};

}  // namespace asyncfem
