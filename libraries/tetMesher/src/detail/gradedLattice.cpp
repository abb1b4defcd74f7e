// SPDX-License-Identifier: BSD-3-Clause
#include "detail/gradedLattice.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <cstdint>
#include <unordered_map>

namespace asyncfem::detail {

namespace {

/// Numbers the lattice vertices of a grid's leaves and emits their tetrahedra, face by face.
class GradedLatticeBuilder {
 public:
  GradedLatticeBuilder(const GradedGrid& grid, GradedLattice& out) : grid_(grid), out_(out) {}

  void build() {
    const std::vector<int> leaves = grid_.leaves();
    // Black vertices (cube corners) first, then red ones (cube centres). A corner lies on the
    // boundary of its leaves and a centre inside its own, so one key never names both.
    for (int c : leaves) {
      const GradedGrid::Cube cube = grid_.cube(c);
      for (int corner = 0; corner < 8; ++corner)
        vertex(cube.corner + cube.size * Eigen::Vector3i(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1));
    }
    for (int c : leaves) vertex(centre(grid_.cube(c)));
    for (int c : leaves)
      for (int axis = 0; axis < 3; ++axis)
        for (int side : {-1, 1}) addFace(c, axis, side);
  }

 private:
  using Square = std::array<Eigen::Vector3i, 4>;

  static Eigen::Vector3i centre(const GradedGrid::Cube& cube) {
    return cube.corner + Eigen::Vector3i::Constant(cube.size / 2);
  }

  long long vertex(const Eigen::Vector3i& d) {
    const auto [it, inserted] =
        ids_.try_emplace(GradedGrid::packKey(d), static_cast<long long>(out_.doubledCoordinates.size()));
    if (inserted) out_.doubledCoordinates.push_back(d);
    return it->second;
  }
  long long existing(const Eigen::Vector3i& d) const {
    const auto it = ids_.find(GradedGrid::packKey(d));
    return it == ids_.end() ? -1LL : it->second;
  }
  long long required(const Eigen::Vector3i& d) const {
    const long long id = existing(d);
    if (id < 0) throw Error("stuffIsosurface: internal error: graded lattice is not balanced");
    return id;
  }
  void emit(const std::array<long long, 4>& tet, bool plain, int ownerA, int ownerB) {
    out_.tetrahedra.push_back(tet);
    out_.plain.push_back(plain ? 1 : 0);
    out_.owners.push_back({ownerA, ownerB});
  }

  /// The corners, in cyclic order, of the face of `cube` normal to `axis` on `side`.
  static Square faceCorners(const GradedGrid::Cube& cube, int axis, int side) {
    const int b = (axis + 1) % 3, d = (axis + 2) % 3, s = cube.size;
    const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    Square square;
    for (std::size_t q = 0; q < 4; ++q) {
      square[q] = cube.corner;
      square[q][axis] = side > 0 ? cube.corner[axis] + s : cube.corner[axis];
      square[q][b] += uv[q][0] * s;
      square[q][d] += uv[q][1] * s;
    }
    return square;
  }

  void addFace(int leaf, int axis, int side) {
    const GradedGrid::Cube cube = grid_.cube(leaf);
    Eigen::Vector3i probe = centre(cube);
    probe[axis] = side > 0 ? cube.corner[axis] + cube.size : cube.corner[axis] - 1;
    const int n = grid_.leafContaining(probe);
    if (n < 0) return;  // the domain's boundary: outside the solid by construction
    const GradedGrid::Cube neighbour = grid_.cube(n);
    const Square square = faceCorners(cube, axis, side);
    if (neighbour.level == cube.level) {
      if (side > 0) addSameSizeFace(leaf, cube, n, axis, square);  // the -a face is the neighbour's +a face
    } else if (neighbour.level < cube.level) {
      addFaceTowardsSmaller(leaf, cube, square);
    } else {
      addFaceTowardsLarger(leaf, cube, neighbour, n, axis, square);
    }
  }

  /// The red edge between the two centres with each edge of the face, bisected at a midpoint
  /// that a smaller cube put there.
  void addSameSizeFace(int leaf, const GradedGrid::Cube& cube, int n, int axis, const Square& square) {
    const long long red = existing(centre(cube));
    const long long otherRed = required(centre(cube) + cube.size * Eigen::Vector3i::Unit(axis));
    for (std::size_t q = 0; q < 4; ++q) {
      const Eigen::Vector3i& u = square[q];
      const Eigen::Vector3i& v = square[(q + 1) % 4];
      const long long mid = existing((u + v) / 2);
      if (mid < 0) {
        emit({existing(u), existing(v), red, otherRed}, cube.level == 0, leaf, n);
      } else {
        emit({existing(u), mid, red, otherRed}, false, leaf, n);
        emit({mid, existing(v), red, otherRed}, false, leaf, n);
      }
    }
  }

  /// Smaller neighbours: eight tetrahedra at the face's centre and edge midpoints.
  void addFaceTowardsSmaller(int leaf, const GradedGrid::Cube& cube, const Square& square) {
    const long long red = existing(centre(cube));
    const long long faceCentre = required((square[0] + square[2]) / 2);
    for (std::size_t q = 0; q < 4; ++q) {
      const Eigen::Vector3i& u = square[q];
      const Eigen::Vector3i& v = square[(q + 1) % 4];
      const long long mid = required((u + v) / 2);
      emit({red, faceCentre, existing(u), mid}, false, leaf, -1);
      emit({red, faceCentre, mid, existing(v)}, false, leaf, -1);
    }
  }

  /// A larger neighbour: split by the diagonal through the centre of its face.
  void addFaceTowardsLarger(int leaf, const GradedGrid::Cube& cube, const GradedGrid::Cube& neighbour, int n, int axis,
                            const Square& square) {
    const long long red = existing(centre(cube));
    Eigen::Vector3i bigCentre = centre(neighbour);
    bigCentre[axis] = square[0][axis];
    std::size_t k = 0;
    while (k < 4 && square[k] != bigCentre) ++k;
    if (k == 4) throw Error("stuffIsosurface: internal error: graded lattice is not balanced");
    auto at = [&](std::size_t q) { return existing(square[(k + q) % 4]); };
    emit({red, at(0), at(1), at(2)}, false, leaf, n);
    emit({red, at(0), at(2), at(3)}, false, leaf, n);
  }

  const GradedGrid& grid_;
  GradedLattice& out_;
  std::unordered_map<std::uint64_t, long long> ids_;
};

}  // namespace

GradedLattice::GradedLattice(const GradedGrid& grid) : origin(grid.origin()), spacing(grid.spacing()) {
  GradedLatticeBuilder(grid, *this).build();
}

std::vector<LatticeEdge> GradedLattice::signChangingEdges(const std::vector<int>& signs) const {
  std::vector<LatticeEdge> edges;
  std::unordered_map<std::uint64_t, char> seen;
  for (std::size_t t = 0; t < tetrahedra.size(); ++t) {
    if (!plain[t]) continue;
    const auto& tet = tetrahedra[t];
    for (std::size_t i = 0; i < 4; ++i)
      for (std::size_t j = i + 1; j < 4; ++j) {
        const long long u = tet[i], v = tet[j];
        if (signs[static_cast<std::size_t>(u)] * signs[static_cast<std::size_t>(v)] >= 0) continue;
        if (seen.emplace(edgeKey(u, v), 1).second) edges.push_back({std::min(u, v), std::max(u, v)});
      }
  }
  return edges;
}

std::vector<int> GradedLattice::leavesMeetingSurface(const std::vector<int>& signs) const {
  std::vector<int> leaves;
  for (std::size_t t = 0; t < tetrahedra.size(); ++t) {
    if (plain[t]) continue;
    const auto& tet = tetrahedra[t];
    const int first = signs[static_cast<std::size_t>(tet[0])];
    bool oneSide = first != 0;
    for (std::size_t i = 1; i < 4 && oneSide; ++i) oneSide = signs[static_cast<std::size_t>(tet[i])] == first;
    if (oneSide) continue;
    for (int owner : owners[t])
      if (owner >= 0) leaves.push_back(owner);
  }
  std::sort(leaves.begin(), leaves.end());
  leaves.erase(std::unique(leaves.begin(), leaves.end()), leaves.end());
  return leaves;
}

}  // namespace asyncfem::detail
