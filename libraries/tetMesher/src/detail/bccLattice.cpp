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

}  // namespace asyncfem::detail
