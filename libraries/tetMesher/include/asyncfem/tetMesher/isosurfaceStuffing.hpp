// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Geometry>
#include <asyncfem/tetMesher/implicit.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>

namespace asyncfem {

/// Largest MesherOptions::gradingLevels (interior cubes of up to 2^6 = 64 spacings).
inline constexpr int kMaxGradingLevels = 6;

/// Settings of stuffIsosurface.
struct MesherOptions {
  /// Warping thresholds of Labelle & Shewchuk 2007 (Section 5): a lattice vertex closer than
  /// alphaLong (axis-parallel edges, length h) or alphaShort (diagonal edges, length
  /// h sqrt(3)/2) times the edge length to a cut point on one of its edges is moved onto
  /// that cut point. With these values and the paper's stencils and parity rule (which this
  /// implementation follows) every dihedral angle lies in [10.78, 164.74] degrees, whatever
  /// the function: the proof uses only the signs at the lattice vertices and the cut points'
  /// positions on their edges, so it also holds for winding-number and other non-distance
  /// functions. Other alphas void the guarantee (and minDihedralDegrees must be lowered).
  double alphaLong = 0.24999;
  double alphaShort = 0.41189;
  /// Iterations of the bracketed root finder that places a cut point on a lattice edge
  /// (it also stops once the bracket is below 1e-12 h).
  int cutPointIterations = 60;
  /// Material of every element (per-set materials are assigned afterwards).
  Material material{"default", 1000.0, 1e6, 0.45};
  /// Evaluate the implicit function at the lattice vertices on all OpenMP threads (the
  /// function must then be safe to call concurrently; the result does not depend on it).
  bool parallel = true;
  /// Where warped vertices pinch two sheets of the boundary together along an edge (parts
  /// thinner than the lattice resolves), move those vertices back to the lattice and
  /// rebuild, so that the boundary has no pinched edge. Off by default: next to such
  /// vertices the angle bound does not hold (minDihedralDegrees is not enforced on a mesh
  /// with such vertices). A pinched boundary is a valid mesh
  /// (checkTetMesh counts pinchedBoundaryEdges); a finer spacing resolves the thin part.
  bool repairPinches = false;
  /// The smallest dihedral angle (degrees) a returned mesh may have. The stuffing bound is
  /// 10.78; an element below this limit means a bug, and stuffIsosurface throws an Error
  /// naming the element and where it is rather than return the mesh. 0 disables it.
  double minDihedralDegrees = 10.0;
  /// Run validateTetMesh on the result and throw if a check fails.
  bool check = true;
  /// 0: a uniform lattice of the given spacing everywhere. N > 0: a graded lattice (the
  /// paper's octree of BCC cubes, strongly balanced): cubes of the given spacing wherever
  /// the surface is within two spacings, growing by factors of two inside, up to 2^N
  /// spacings. Near the surface the mesh is the uniform one, so the angle bound and the
  /// stencils are unchanged; the interior has far fewer, larger elements (their shapes:
  /// BCC tetrahedra, bisected ones and pyramid halves, dihedral angles 45 to 120 degrees). Cubes are
  /// refined where |f| at their centre is below their half-diagonal plus one spacing, which
  /// finds the surface wherever |f| is at most the distance to it (signed distances,
  /// SignedDistance, this library's primitives and their unions); a coarse tetrahedron whose
  /// vertices still differ in sign, or touch a warped vertex, is refined afterwards, so the
  /// mesh is valid and bounded for any f, but an f much steeper than a distance can lose
  /// surface detail inside coarse cubes.
  int gradingLevels = 0;
  /// Largest number of lattice vertices accepted (guards against a spacing far too small).
  long long maxLatticeVertices = 200'000'000;
};

/// What stuffIsosurface did, for reports.
struct StuffingReport {
  long long latticeVertices = 0;  ///< black + red BCC lattice vertices evaluated
  long long latticeTetrahedra = 0;
  int cutPoints = 0;         ///< cut points used as mesh vertices
  int warpedVertices = 0;    ///< lattice vertices moved onto the surface
  int unwarpedVertices = 0;  ///< warped vertices moved back to undo boundary pinches
  int elements = 0;
  int vertices = 0;
  int pinchedBoundaryEdges = 0;     ///< see MeshCheckReport::pinchedBoundaryEdges
  double minDihedralDegrees = 0.0;  ///< of the returned mesh
  double maxDihedralDegrees = 0.0;
  int gradingLevels = 0;       ///< MesherOptions::gradingLevels used
  long long latticeCells = 0;  ///< leaf cubes of the graded lattice (0 for a uniform one)
  int refinementRounds = 0;    ///< extra refinements where the surface reached a coarse cube
};

/// Tetrahedral mesh of the solid {x : f(x) < 0} inside bounds, by isosurface stuffing
/// (Labelle & Shewchuk, "Isosurface Stuffing: Fast Tetrahedral Meshes with Good Dihedral
/// Angles", SIGGRAPH 2007) on a body-centred cubic lattice of spacing h:
/// 1. f is sampled at the BCC lattice vertices (cube corners, "black", and cube centres,
///    "red") covering bounds plus a margin of two cells; bounds must contain the solid.
/// 2. Every lattice edge whose end values have opposite signs gets a cut point, the root
///    of f on the edge.
/// 3. A vertex closer to a cut point on one of its edges than alpha times that edge's
///    length is warped onto the closest such cut point and its value set to zero; cut
///    points on edges of warped vertices are dropped.
/// 4. Each BCC tetrahedron is filled by the paper's stencil for the signs (-, 0, +) of its
///    vertices: whole tetrahedra, single tetrahedra cut from a corner, pyramids (two
///    tetrahedra) and prisms (three). Quadrilaterals in lattice faces are split by the
///    paper's rule (long edge, else parity), which depends only on the face.
/// The elements are positively oriented, all get options.material; no sets are created.
/// With options.check the result is validated (validateTetMesh) and a ValidationError
/// names the first failed check; an element below options.minDihedralDegrees is an Error. ValidationError for a spacing
/// <= 0, an empty or oversized lattice, or an empty result.
TetMesh stuffIsosurface(const ImplicitFunction& f, const Eigen::AlignedBox3d& bounds, double spacing,
                        const MesherOptions& options = {}, StuffingReport* report = nullptr);

}  // namespace asyncfem
