// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/tetMesher/implicit.hpp>
#include <asyncfem/tetMesher/signedDistance.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <string>

namespace asyncfem {

/// How far a mesh's boundary lies from the surface it was made from, both ways (the two
/// one-sided Hausdorff distances), measured at sample points: the vertices, edge midpoints
/// and centroids of the triangles on each side. Each maximum comes with where it occurs.
struct SurfaceDeviation {
  double meshToSurface = 0.0;  ///< max over the mesh boundary of the distance to the surface
  Eigen::Vector3d meshToSurfaceAt = Eigen::Vector3d::Zero();
  double surfaceToMesh = 0.0;  ///< max over the input surface of the distance to the boundary
  Eigen::Vector3d surfaceToMeshAt = Eigen::Vector3d::Zero();
  int surfaceToMeshTriangle = -1;  ///< triangle of distance.surface() holding surfaceToMeshAt
  double hausdorff() const { return meshToSurface > surfaceToMesh ? meshToSurface : surfaceToMesh; }
};

/// Sampled Hausdorff distance between the boundary of `mesh` and `surface` (the triangles of
/// distance.surface()). Cost: one closest-point query per sample on each side (BVH).
SurfaceDeviation surfaceDeviation(const TetMesh& mesh, const SignedDistance& distance);

/// For an implicit solid: the largest |f| over the same boundary samples (f is a distance or
/// a bound of one near the surface, implicit.hpp), i.e. the mesh-to-surface side only.
double implicitDeviation(const TetMesh& mesh, const ImplicitFunction& f, Eigen::Vector3d* where = nullptr);

/// The surface made of the mesh's boundary triangles (outward), one part "boundary".
TriangleSurface boundaryTriangleSurface(const TetMesh& mesh);

/// Throws a ValidationError when the mesh was built from an open surface through the winding
/// number and had to invent too much of its boundary: more than maxFraction of the boundary
/// area lies farther than `spacing` from every input triangle (the patches the winding number
/// spans across holes). The message names the farthest such point and its nearest input
/// triangle; `source` starts it (a file name). Returns the invented fraction otherwise.
double requireRepairableHoles(const TetMesh& mesh, const SignedDistance& distance, double spacing, double maxFraction,
                              const std::string& source);

/// Throws a ValidationError when a closed surface overlaps itself: the generalized winding
/// number at some element centroid (tetrahedra or hexahedra; checked at up to maxSamples of them, evenly spread)
/// exceeds 1.5, i.e. the point is inside two shells; names the place and the nearest
/// triangle, and points to the winding-number mode (which meshes the union).
void requireNoSelfOverlap(const TetMesh& mesh, const SignedDistance& distance, const std::string& source,
                          int maxSamples = 4000);

}  // namespace asyncfem
