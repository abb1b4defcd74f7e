// SPDX-License-Identifier: BSD-3-Clause
// Internal to the tetMesher library: the octree under the graded lattice of isosurface stuffing.
#pragma once

#include <Eigen/Geometry>
#include <asyncfem/tetMesher/implicit.hpp>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace asyncfem::detail {

/// A strongly balanced octree over a grid of root cubes of 2^levels spacings: leaves whose
/// neighbours across a face, an edge or a corner differ from them by at most one level.
/// Coordinates are doubled lattice coordinates (units of half a finest spacing from the
/// origin), so finest cube centres are integers too.
class GradedGrid {
 public:
  /// One cube: its lowest corner, edge length (doubled units: 2^(level+1)) and level (0: finest).
  struct Cube {
    Eigen::Vector3i corner;
    int size = 0;
    int level = 0;
  };

  /// Root cubes of 2^levels * spacing, `roots` of them along each axis, from `origin`.
  /// Refinement that would make more than maxCells cubes (leaves and parents) throws a
  /// ValidationError instead of exhausting memory.
  GradedGrid(const Eigen::Vector3d& origin, double spacing, int levels, const Eigen::Array3i& roots,
             long long maxCells);
  /// Root cubes covering `bounds` plus a margin of at least two spacings, in whole root
  /// cubes, so the outermost cubes lie outside the solid. ValidationError when a side would
  /// need more than 10^6 finest cells.
  static GradedGrid covering(const Eigen::AlignedBox3d& bounds, double spacing, int levels, long long maxCells);

  /// Splits, level by level, every cube of size s whose centre c has |f(c)| < s sqrt(3)/2 +
  /// band, so that (for a 1-Lipschitz f) every point within `band` of the surface lies in a
  /// finest cube; then balances. f values at cube centres are kept (values()).
  void refineNear(const ImplicitFunction& f, double band, bool parallel);
  /// Splits the given leaves (those of level 0 are left alone) and rebalances; returns the
  /// number split.
  int splitLeaves(const std::vector<int>& leaves);

  /// Ids of the leaves, in increasing order.
  std::vector<int> leaves() const;
  Cube cube(int id) const {
    const Cell& cell = cells_[static_cast<std::size_t>(id)];
    return {cell.corner, size(cell), cell.level};
  }
  /// The leaf whose half-open box holds `point` (doubled coordinates), or -1 outside the grid.
  int leafContaining(const Eigen::Vector3i& point) const;
  int numLeaves() const;
  int numCells() const { return static_cast<int>(cells_.size()); }
  Eigen::Vector3d origin() const { return origin_; }
  double spacing() const { return spacing_; }
  int levels() const { return levels_; }
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
  void split(int cell);
  void balance();
  bool balanceAround(const Cell& cell);
  std::vector<int> splitWhereSurfaceIsNear(const std::vector<int>& cubes, const ImplicitFunction& f, double band,
                                           bool parallel);

  Eigen::Vector3d origin_;
  double spacing_;
  int levels_;
  Eigen::Array3i roots_;
  long long maxCells_;
  std::vector<Cell> cells_;
  std::unordered_map<std::uint64_t, double> values_;
};

}  // namespace asyncfem::detail
