// SPDX-License-Identifier: BSD-3-Clause
// Internal to the tetMesher library: the uniform body-centred cubic lattice.
#pragma once

#include <Eigen/Geometry>
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
  Eigen::Vector3i doubled(long long id) const;
  Eigen::Vector3d position(long long id) const;

  /// Sign-changing edges in the order: black edges (vertex by vertex, +x, +y, +z), then per
  /// cube its red edges (+x, +y, +z) and its eight short edges to the corners (red first).
  /// Every lattice edge counts, including those of no tetrahedron on the outer faces.
  std::vector<LatticeEdge> signChangingEdges(const std::vector<int>& signs) const;
  /// Each BCC tetrahedron pairs the red edge between two face-adjacent cube centres with one
  /// of the four black edges of the face they share; cube by cube, axis by axis.
  long long forEachTetrahedron(const TetrahedronVisitor& visit) const;

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
  Eigen::Array3i indices(long long id) const;
  void addBlackEdges(const std::vector<int>& signs, std::vector<LatticeEdge>& edges) const;
  void addRedEdges(const std::vector<int>& signs, std::vector<LatticeEdge>& edges) const;
  long long visitFace(const Eigen::Array3i& cube, int axis, const TetrahedronVisitor& visit) const;

  Eigen::Vector3d origin_;
  double spacing_ = 0.0;
  Eigen::Array3i cells_;  // cubes per axis
};

}  // namespace asyncfem::detail
