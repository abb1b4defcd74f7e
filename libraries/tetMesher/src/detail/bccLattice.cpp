// SPDX-License-Identifier: BSD-3-Clause
#include "detail/bccLattice.hpp"

#include <asyncfem/core/error.hpp>
#include <cmath>

namespace asyncfem::detail {

BccLattice::BccLattice(const Eigen::AlignedBox3d& bounds, double spacing)
    : origin_(bounds.min() - Eigen::Vector3d::Constant(2.0 * spacing)), spacing_(spacing) {
  const Eigen::Array3d extent = (bounds.max() - bounds.min()).array() / spacing;
  for (int a = 0; a < 3; ++a) {
    const double cells = std::ceil(extent[a]) + 4.0;
    if (cells > 1e6) throw ValidationError("stuffIsosurface: spacing too small for the bounds");
    cells_[a] = static_cast<int>(cells);
  }
}

Eigen::Array3i BccLattice::indices(long long id) const {
  const bool red = isRed(id);
  const long long index = red ? id - numBlack() : id;
  const long long nx = red ? cells_.x() : cells_.x() + 1, ny = red ? cells_.y() : cells_.y() + 1;
  return {static_cast<int>(index % nx), static_cast<int>((index / nx) % ny), static_cast<int>(index / (nx * ny))};
}

Eigen::Vector3i BccLattice::doubled(long long id) const {
  const Eigen::Vector3i twice = 2 * indices(id).matrix();
  return isRed(id) ? Eigen::Vector3i(twice + Eigen::Vector3i::Ones()) : twice;
}

Eigen::Vector3d BccLattice::position(long long id) const {
  const Eigen::Vector3d index = indices(id).cast<double>().matrix();
  if (!isRed(id)) return origin_ + spacing_ * index;
  return origin_ + spacing_ * Eigen::Vector3d(index.x() + 0.5, index.y() + 0.5, index.z() + 0.5);
}

namespace {

void addIfSignChanges(const std::vector<int>& signs, long long from, long long to, std::vector<LatticeEdge>& edges) {
  if (signs[static_cast<std::size_t>(from)] * signs[static_cast<std::size_t>(to)] < 0) edges.push_back({from, to});
}

}  // namespace

void BccLattice::addBlackEdges(const std::vector<int>& signs, std::vector<LatticeEdge>& edges) const {
  const Eigen::Array3i& n = cells_;
  for (int k = 0; k <= n.z(); ++k)
    for (int j = 0; j <= n.y(); ++j)
      for (int i = 0; i <= n.x(); ++i) {
        const long long b = black(i, j, k);
        if (i < n.x()) addIfSignChanges(signs, b, black(i + 1, j, k), edges);
        if (j < n.y()) addIfSignChanges(signs, b, black(i, j + 1, k), edges);
        if (k < n.z()) addIfSignChanges(signs, b, black(i, j, k + 1), edges);
      }
}

void BccLattice::addRedEdges(const std::vector<int>& signs, std::vector<LatticeEdge>& edges) const {
  const Eigen::Array3i& n = cells_;
  for (int k = 0; k < n.z(); ++k)
    for (int j = 0; j < n.y(); ++j)
      for (int i = 0; i < n.x(); ++i) {
        const long long r = red(i, j, k);
        if (i + 1 < n.x()) addIfSignChanges(signs, r, red(i + 1, j, k), edges);
        if (j + 1 < n.y()) addIfSignChanges(signs, r, red(i, j + 1, k), edges);
        if (k + 1 < n.z()) addIfSignChanges(signs, r, red(i, j, k + 1), edges);
        for (int corner = 0; corner < 8; ++corner) {
          addIfSignChanges(signs, r, black(i + (corner & 1), j + ((corner >> 1) & 1), k + ((corner >> 2) & 1)), edges);
        }
      }
}

std::vector<LatticeEdge> BccLattice::signChangingEdges(const std::vector<int>& signs) const {
  std::vector<LatticeEdge> edges;
  addBlackEdges(signs, edges);
  addRedEdges(signs, edges);
  return edges;
}

long long BccLattice::visitFace(const Eigen::Array3i& cube, int axis, const TetrahedronVisitor& visit) const {
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
  for (const auto& edge : blackEdges) visit({edge[0], edge[1], r0, r1});
  return static_cast<long long>(blackEdges.size());
}

long long BccLattice::forEachTetrahedron(const TetrahedronVisitor& visit) const {
  long long count = 0;
  for (int k = 0; k < cells_.z(); ++k)
    for (int j = 0; j < cells_.y(); ++j)
      for (int i = 0; i < cells_.x(); ++i)
        for (int axis = 0; axis < 3; ++axis) count += visitFace(Eigen::Array3i(i, j, k), axis, visit);
  return count;
}

}  // namespace asyncfem::detail
