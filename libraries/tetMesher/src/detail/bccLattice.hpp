// SPDX-License-Identifier: BSD-3-Clause
// Internal to the tetMesher library: the uniform body-centred cubic lattice.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <vector>

#include "detail/lattice.hpp"

namespace asyncfem::detail {

/// The uniform body-centred cubic lattice of spacing h (a StuffingLattice): black vertices at
/// the corners of `cells` cubes of size h, red vertices at their centres. Ids: black first
/// (x fastest), then red. Nothing is stored: ids, edges and tetrahedra follow from indices,
/// so a lattice of 10^8 vertices costs only its samples.
class BccLattice {
 public:
  /// Covers `bounds` plus two cells on each side, so that the outermost lattice layers lie
  /// outside the solid. ValidationError when a side would need more than 10^6 cells.
  BccLattice(const Eigen::AlignedBox3d& bounds, double spacing);

  long long numVertices() const { return numBlack() + numRed(); }
  bool isRed(long long id) const { return id >= numBlack(); }
  /// Twice the lattice coordinates: black (2i, 2j, 2k), red (2i+1, 2j+1, 2k+1).
  Eigen::Vector3i doubled(long long id) const {
    const Eigen::Vector3i twice = 2 * indices(id).matrix();
    return isRed(id) ? Eigen::Vector3i(twice + Eigen::Vector3i::Ones()) : twice;
  }
  Eigen::Vector3d position(long long id) const {
    const Eigen::Vector3d index = indices(id).cast<double>().matrix();
    if (!isRed(id)) return origin_ + spacing_ * index;
    return origin_ + spacing_ * Eigen::Vector3d(index.x() + 0.5, index.y() + 0.5, index.z() + 0.5);
  }

  /// Sign-changing edges in the order: black edges (vertex by vertex, +x, +y, +z), then per
  /// cube its red edges (+x, +y, +z) and its eight short edges to the corners (red first).
  /// Every lattice edge counts, including those of no tetrahedron on the outer faces.
  std::vector<LatticeEdge> signChangingEdges(const std::vector<int>& signs) const;
  /// Each BCC tetrahedron pairs the red edge between two face-adjacent cube centres with one
  /// of the four black edges of the face they share; cube by cube, axis by axis.
  /// (A template, not a TetrahedronVisitor, so that the stencils' per-tetrahedron call inlines.)
  template <class Visit>
  long long forEachTetrahedron(Visit&& visit) const {
    long long count = 0;
    for (int k = 0; k < cells_.z(); ++k)
      for (int j = 0; j < cells_.y(); ++j)
        for (int i = 0; i < cells_.x(); ++i)
          for (int axis = 0; axis < 3; ++axis) count += visitFace(Eigen::Array3i(i, j, k), axis, visit);
    return count;
  }

 private:
  long long numBlack() const { return static_cast<long long>(cells_.x() + 1) * (cells_.y() + 1) * (cells_.z() + 1); }
  long long numRed() const { return static_cast<long long>(cells_.x()) * cells_.y() * cells_.z(); }
  long long black(int i, int j, int k) const {
    return i + static_cast<long long>(cells_.x() + 1) * (j + static_cast<long long>(cells_.y() + 1) * k);
  }
  long long black(const Eigen::Array3i& corner) const { return black(corner.x(), corner.y(), corner.z()); }
  long long red(int i, int j, int k) const {
    return numBlack() + i + static_cast<long long>(cells_.x()) * (j + static_cast<long long>(cells_.y()) * k);
  }
  /// Lattice indices of a vertex: (i, j, k) of a black corner or of a red vertex's cube.
  Eigen::Array3i indices(long long id) const {
    const bool red = isRed(id);
    const long long index = red ? id - numBlack() : id;
    const long long nx = red ? cells_.x() : cells_.x() + 1, ny = red ? cells_.y() : cells_.y() + 1;
    return {static_cast<int>(index % nx), static_cast<int>((index / nx) % ny), static_cast<int>(index / (nx * ny))};
  }
  void addBlackEdges(const std::vector<int>& signs, std::vector<LatticeEdge>& edges) const;
  void addRedEdges(const std::vector<int>& signs, std::vector<LatticeEdge>& edges) const;
  /// The four tetrahedra across the +axis face of `cube` (none on the lattice's far side).
  template <class Visit>
  long long visitFace(const Eigen::Array3i& cube, int axis, Visit& visit) const {
    Eigen::Array3i next = cube;
    ++next[axis];
    if (next[axis] >= cells_[axis]) return 0;
    const long long r0 = red(cube.x(), cube.y(), cube.z()), r1 = red(next.x(), next.y(), next.z());
    const int b = (axis + 1) % 3, d = (axis + 2) % 3;
    auto corner = [&](int s, int t) {
      Eigen::Array3i c = next;
      c[b] += s;
      c[d] += t;
      return black(c);
    };
    const std::array<std::array<long long, 2>, 4> blackEdges{{{corner(0, 0), corner(1, 0)},
                                                              {corner(0, 1), corner(1, 1)},
                                                              {corner(0, 0), corner(0, 1)},
                                                              {corner(1, 0), corner(1, 1)}}};
    for (const auto& edge : blackEdges) visit(std::array<long long, 4>{edge[0], edge[1], r0, r1});
    return static_cast<long long>(blackEdges.size());
  }

  Eigen::Vector3d origin_;
  double spacing_ = 0.0;
  Eigen::Array3i cells_;  // cubes per axis
};

}  // namespace asyncfem::detail
