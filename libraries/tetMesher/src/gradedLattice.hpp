// SPDX-License-Identifier: BSD-3-Clause
// Internal to the tetMesher library: the graded background grid of isosurface stuffing.
#pragma once

#include <Eigen/Core>
#include <array>
#include <asyncfem/tetMesher/implicit.hpp>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace asyncfem::detail {

/// Tetrahedra of a graded body-centred cubic grid, with the interface of the uniform lattice
/// that the stuffing stencils use: vertex ids, doubled integer coordinates (units of half a
/// spacing from the origin) and red-ness.
struct GradedTetrahedra {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double spacing = 0.0;
  std::vector<Eigen::Vector3i> doubledCoordinates;  ///< per vertex
  std::vector<std::array<long long, 4>> tetrahedra;
  /// Per tetrahedron: true for a tetrahedron of the finest uniform BCC lattice (two
  /// face-adjacent finest cube centres and an edge of their shared face). Only those may be
  /// cut by the surface or touch a warped vertex; the others are kept whole or dropped.
  std::vector<char> plain;
  /// Per tetrahedron: the octree leaves it was made from (the second is -1 for a pyramid
  /// inside one cube).
  std::vector<std::array<int, 2>> owners;

  long long numVertices() const { return static_cast<long long>(doubledCoordinates.size()); }
  Eigen::Vector3i doubled(long long id) const { return doubledCoordinates[static_cast<std::size_t>(id)]; }
  /// Red vertices of the finest lattice are the finest cube centres: all doubled coordinates odd.
  bool isRed(long long id) const {
    const Eigen::Vector3i& d = doubledCoordinates[static_cast<std::size_t>(id)];
    return (d.x() & 1) != 0 && (d.y() & 1) != 0 && (d.z() & 1) != 0;
  }
  Eigen::Vector3d position(long long id) const {
    return origin + 0.5 * spacing * doubledCoordinates[static_cast<std::size_t>(id)].cast<double>();
  }
};

/// A strongly balanced octree over a grid of root cubes of 2^levels spacings: leaves whose
/// neighbours across a face, an edge or a corner differ from them by at most one level.
class GradedGrid {
 public:
  /// Root cubes of 2^levels * spacing, `roots` of them along each axis, from `origin`.
  /// Refinement that would make more than maxCells cubes (leaves and parents) throws a
  /// ValidationError instead of exhausting memory.
  GradedGrid(const Eigen::Vector3d& origin, double spacing, int levels, const Eigen::Array3i& roots,
             long long maxCells);

  /// Splits, level by level, every cube of size s whose centre c has |f(c)| < s sqrt(3)/2 +
  /// band, so that (for a 1-Lipschitz f) every point within `band` of the surface lies in a
  /// finest cube; then balances. f values at cube centres are kept (values()).
  void refineNear(const ImplicitFunction& f, double band, bool parallel);
  /// Splits the given leaves (those of level 0 are left alone) and rebalances; returns the
  /// number split.
  int splitLeaves(const std::vector<int>& leaves);
  /// The graded tetrahedra of the current leaves (Labelle & Shewchuk 2007, Section 6):
  /// across a face between two leaves of one size, the tetrahedra of the red edge joining
  /// their centres with each edge of the face (bisected where a smaller cube put a vertex at
  /// the edge's midpoint); across a face towards smaller leaves, the pyramid from the
  /// centre to the face split into eight at the face's centre and edge midpoints; across a
  /// face towards a larger leaf, that pyramid split into two by the diagonal through the
  /// larger face's centre, which is how the larger side splits it.
  GradedTetrahedra tetrahedra() const;

  int numLeaves() const;
  int numCells() const { return static_cast<int>(cells_.size()); }
  /// f at points already evaluated, keyed by packed doubled coordinates (packKey).
  const std::unordered_map<std::uint64_t, double>& values() const { return values_; }
  static std::uint64_t packKey(const Eigen::Vector3i& doubled);

 private:
  struct Cell {
    Eigen::Vector3i corner;  // doubled coordinates
    int level = 0;
    int firstChild = -1;
  };
  int size(const Cell& c) const { return 2 << c.level; }  // edge length in doubled units
  int locate(const Eigen::Vector3i& point) const;         // leaf whose half-open box holds point, or -1
  void split(int cell);
  void balance();

  Eigen::Vector3d origin_;
  double spacing_;
  int levels_;
  Eigen::Array3i roots_;
  long long maxCells_;
  std::vector<Cell> cells_;
  std::unordered_map<std::uint64_t, double> values_;
};

}  // namespace asyncfem::detail
