// SPDX-License-Identifier: BSD-3-Clause
#include "detail/gradedGrid.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <cmath>
#include <cstdlib>
#include <string>

namespace asyncfem::detail {

namespace {

constexpr int kKeyBits = 21;  // doubled coordinates below 2^21 per axis (checked by the caller)

}  // namespace

std::uint64_t GradedGrid::packKey(const Eigen::Vector3i& d) {
  return static_cast<std::uint64_t>(d.x()) | (static_cast<std::uint64_t>(d.y()) << kKeyBits) |
         (static_cast<std::uint64_t>(d.z()) << (2 * kKeyBits));
}

GradedGrid::GradedGrid(const Eigen::Vector3d& origin, double spacing, int levels, const Eigen::Array3i& roots,
                       long long maxCells)
    : origin_(origin), spacing_(spacing), levels_(levels), roots_(roots), maxCells_(maxCells) {
  // In 64 bits: up to 10^6 finest cells per side, the root count overflows an int.
  const long long numRoots = static_cast<long long>(roots.x()) * roots.y() * roots.z();
  if (numRoots > maxCells_) {
    throw ValidationError("stuffIsosurface: the graded lattice would have " + std::to_string(numRoots) +
                          " root cubes (limit " + std::to_string(maxCells_) + "); use a larger spacing");
  }
  const long long rootSize = 2LL << levels;
  for (int a = 0; a < 3; ++a) {
    if (rootSize * roots[a] >= (1LL << kKeyBits)) {
      throw ValidationError(
          "stuffIsosurface: the graded lattice is too large for its coordinates; use a larger spacing");
    }
  }
  cells_.reserve(static_cast<std::size_t>(numRoots));
  for (int k = 0; k < roots.z(); ++k)
    for (int j = 0; j < roots.y(); ++j)
      for (int i = 0; i < roots.x(); ++i)
        cells_.push_back(Cell{static_cast<int>(rootSize) * Eigen::Vector3i(i, j, k), levels, -1});
}

GradedGrid GradedGrid::covering(const Eigen::AlignedBox3d& bounds, double spacing, int levels, long long maxCells) {
  const double rootEdge = spacing * static_cast<double>(1 << levels);
  const double margin = rootEdge * std::ceil(2.0 * spacing / rootEdge);
  const Eigen::Vector3d origin = bounds.min() - Eigen::Vector3d::Constant(margin);
  Eigen::Array3i roots;
  for (int a = 0; a < 3; ++a) {
    const double cells = std::ceil((bounds.max()[a] - bounds.min()[a] + 2.0 * margin) / rootEdge);
    if (cells * static_cast<double>(1 << levels) > 1e6) {
      throw ValidationError("stuffIsosurface: spacing too small for the bounds");
    }
    roots[a] = static_cast<int>(cells);
  }
  return GradedGrid(origin, spacing, levels, roots, maxCells);
}

int GradedGrid::leafContaining(const Eigen::Vector3i& p) const {
  const int rootSize = 2 << levels_;
  Eigen::Array3i root;
  for (int a = 0; a < 3; ++a) {
    if (p[a] < 0 || p[a] >= rootSize * roots_[a]) return -1;
    root[a] = p[a] / rootSize;
  }
  int c = root.x() + roots_.x() * (root.y() + roots_.y() * root.z());
  while (cells_[static_cast<std::size_t>(c)].firstChild >= 0) {
    const Cell& cell = cells_[static_cast<std::size_t>(c)];
    const int half = size(cell) / 2;
    int child = 0;
    for (int a = 0; a < 3; ++a)
      if (p[a] >= cell.corner[a] + half) child |= 1 << a;
    c = cell.firstChild + child;
  }
  return c;
}

void GradedGrid::split(int c) {
  if (static_cast<long long>(cells_.size()) + 8 > maxCells_) {
    throw ValidationError("stuffIsosurface: the graded lattice would have more than " + std::to_string(maxCells_) +
                          " cubes at spacing " + std::to_string(spacing_) + "; use a larger spacing");
  }
  const Cell parent = cells_[static_cast<std::size_t>(c)];
  const int half = size(parent) / 2;
  cells_[static_cast<std::size_t>(c)].firstChild = static_cast<int>(cells_.size());
  for (int child = 0; child < 8; ++child) {
    const Eigen::Vector3i offset((child & 1) * half, ((child >> 1) & 1) * half, ((child >> 2) & 1) * half);
    cells_.push_back(Cell{parent.corner + offset, parent.level - 1, -1});
  }
}

bool GradedGrid::balanceAround(const Cell& cell) {
  bool changed = false;
  const int s = size(cell);
  for (int o = 0; o < 27; ++o) {
    if (o == 13) continue;  // the cell itself
    const int offset[3] = {o % 3 - 1, (o / 3) % 3 - 1, o / 9 - 1};
    Eigen::Vector3i probe;
    for (int a = 0; a < 3; ++a)
      probe[a] = offset[a] < 0 ? cell.corner[a] - 1 : (offset[a] > 0 ? cell.corner[a] + s : cell.corner[a] + s / 2);
    for (int n = leafContaining(probe); n >= 0 && cells_[static_cast<std::size_t>(n)].level > cell.level + 1;
         n = leafContaining(probe)) {
      split(n);
      changed = true;
    }
  }
  return changed;
}

void GradedGrid::balance() {
  bool changed = true;
  while (changed) {
    changed = false;
    for (std::size_t c = 0; c < cells_.size(); ++c) {
      if (cells_[c].firstChild >= 0) continue;
      const Cell cell = cells_[c];  // a copy: splitting neighbours grows cells_
      if (balanceAround(cell)) changed = true;
    }
  }
}

void GradedGrid::refineNear(const ImplicitFunction& f, double band, bool parallel) {
  std::vector<int> current;
  for (int c = 0; c < static_cast<int>(cells_.size()); ++c)
    if (cells_[static_cast<std::size_t>(c)].firstChild < 0 && cells_[static_cast<std::size_t>(c)].level > 0)
      current.push_back(c);
  while (!current.empty()) current = splitWhereSurfaceIsNear(current, f, band, parallel);
  balance();
}

std::vector<int> GradedGrid::splitWhereSurfaceIsNear(const std::vector<int>& cubes, const ImplicitFunction& f,
                                                     double band, bool parallel) {
  const double halfDiagonal = 0.5 * std::sqrt(3.0);
  std::vector<Eigen::Vector3i> centres(cubes.size());
  std::vector<double> centreValues(cubes.size());
  for (std::size_t i = 0; i < cubes.size(); ++i) {
    const Cell& cell = cells_[static_cast<std::size_t>(cubes[i])];
    centres[i] = cell.corner + Eigen::Vector3i::Constant(size(cell) / 2);
  }
  const long long count = static_cast<long long>(cubes.size());
#pragma omp parallel for schedule(dynamic, 64) if (parallel)
  for (long long i = 0; i < count; ++i) {
    const std::size_t u = static_cast<std::size_t>(i);
    centreValues[u] = f(origin_ + 0.5 * spacing_ * centres[u].cast<double>());
  }
  std::vector<int> children;  // the next level's candidates
  for (std::size_t i = 0; i < cubes.size(); ++i) {
    if (!std::isfinite(centreValues[i])) {
      throw ValidationError("stuffIsosurface: the implicit function returned a non-finite value");
    }
    values_.emplace(packKey(centres[i]), centreValues[i]);
    const int c = cubes[i];
    const int level = cells_[static_cast<std::size_t>(c)].level;
    const double edge = spacing_ * static_cast<double>(1 << level);
    if (std::abs(centreValues[i]) >= halfDiagonal * edge + band) continue;
    split(c);
    if (level - 1 > 0) {
      const int first = cells_[static_cast<std::size_t>(c)].firstChild;
      for (int child = 0; child < 8; ++child) children.push_back(first + child);
    }
  }
  return children;
}

int GradedGrid::splitLeaves(const std::vector<int>& leaves) {
  int count = 0;
  for (int c : leaves) {
    const Cell& cell = cells_[static_cast<std::size_t>(c)];
    if (cell.firstChild >= 0 || cell.level == 0) continue;
    split(c);
    ++count;
  }
  if (count > 0) balance();
  return count;
}

std::vector<int> GradedGrid::leaves() const {
  std::vector<int> ids;
  for (int c = 0; c < static_cast<int>(cells_.size()); ++c)
    if (cells_[static_cast<std::size_t>(c)].firstChild < 0) ids.push_back(c);
  return ids;
}

int GradedGrid::numLeaves() const {
  return static_cast<int>(std::count_if(cells_.begin(), cells_.end(), [](const Cell& c) { return c.firstChild < 0; }));
}

}  // namespace asyncfem::detail
