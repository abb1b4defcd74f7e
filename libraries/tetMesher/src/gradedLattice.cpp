// SPDX-License-Identifier: BSD-3-Clause
#include "gradedLattice.hpp"

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
  if (static_cast<long long>(roots.prod()) > maxCells_) {
    throw ValidationError("stuffIsosurface: the graded lattice would have " + std::to_string(roots.prod()) +
                          " root cubes (limit " + std::to_string(maxCells_) + "); use a larger spacing");
  }
  const long long rootSize = 2LL << levels;
  for (int a = 0; a < 3; ++a) {
    if (rootSize * roots[a] >= (1LL << kKeyBits)) {
      throw ValidationError(
          "stuffIsosurface: the graded lattice is too large for its coordinates; use a larger spacing");
    }
  }
  cells_.reserve(static_cast<std::size_t>(roots.prod()));
  for (int k = 0; k < roots.z(); ++k)
    for (int j = 0; j < roots.y(); ++j)
      for (int i = 0; i < roots.x(); ++i)
        cells_.push_back(Cell{static_cast<int>(rootSize) * Eigen::Vector3i(i, j, k), levels, -1});
}

int GradedGrid::locate(const Eigen::Vector3i& p) const {
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

void GradedGrid::balance() {
  bool changed = true;
  while (changed) {
    changed = false;
    for (std::size_t c = 0; c < cells_.size(); ++c) {
      if (cells_[c].firstChild >= 0) continue;
      const Cell cell = cells_[c];
      const int s = size(cell);
      for (int o = 0; o < 27; ++o) {
        if (o == 13) continue;  // the cell itself
        const int offset[3] = {o % 3 - 1, (o / 3) % 3 - 1, o / 9 - 1};
        Eigen::Vector3i probe;
        for (int a = 0; a < 3; ++a)
          probe[a] = offset[a] < 0 ? cell.corner[a] - 1 : (offset[a] > 0 ? cell.corner[a] + s : cell.corner[a] + s / 2);
        for (int n = locate(probe); n >= 0 && cells_[static_cast<std::size_t>(n)].level > cell.level + 1;
             n = locate(probe)) {
          split(n);
          changed = true;
        }
      }
    }
  }
}

void GradedGrid::refineNear(const ImplicitFunction& f, double band, bool parallel) {
  std::vector<int> current;
  for (int c = 0; c < static_cast<int>(cells_.size()); ++c)
    if (cells_[static_cast<std::size_t>(c)].firstChild < 0 && cells_[static_cast<std::size_t>(c)].level > 0)
      current.push_back(c);
  const double halfDiagonal = 0.5 * std::sqrt(3.0);
  while (!current.empty()) {
    std::vector<Eigen::Vector3i> centres(current.size());
    std::vector<double> centreValues(current.size());
    for (std::size_t i = 0; i < current.size(); ++i) {
      const Cell& cell = cells_[static_cast<std::size_t>(current[i])];
      centres[i] = cell.corner + Eigen::Vector3i::Constant(size(cell) / 2);
    }
    const long long count = static_cast<long long>(current.size());
#pragma omp parallel for schedule(dynamic, 64) if (parallel)
    for (long long i = 0; i < count; ++i) {
      const std::size_t u = static_cast<std::size_t>(i);
      centreValues[u] = f(origin_ + 0.5 * spacing_ * centres[u].cast<double>());
    }
    std::vector<int> next;
    for (std::size_t i = 0; i < current.size(); ++i) {
      if (!std::isfinite(centreValues[i])) {
        throw ValidationError("stuffIsosurface: the implicit function returned a non-finite value");
      }
      values_.emplace(packKey(centres[i]), centreValues[i]);
      const int c = current[i];
      const int level = cells_[static_cast<std::size_t>(c)].level;
      const double edge = spacing_ * static_cast<double>(1 << level);
      if (std::abs(centreValues[i]) >= halfDiagonal * edge + band) continue;
      split(c);
      if (level - 1 > 0) {
        const int first = cells_[static_cast<std::size_t>(c)].firstChild;
        for (int child = 0; child < 8; ++child) next.push_back(first + child);
      }
    }
    current = std::move(next);
  }
  balance();
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

int GradedGrid::numLeaves() const {
  return static_cast<int>(std::count_if(cells_.begin(), cells_.end(), [](const Cell& c) { return c.firstChild < 0; }));
}

GradedTetrahedra GradedGrid::tetrahedra() const {
  GradedTetrahedra out;
  out.origin = origin_;
  out.spacing = spacing_;
  std::unordered_map<std::uint64_t, long long> ids;
  auto vertex = [&](const Eigen::Vector3i& d) {
    const auto [it, inserted] = ids.try_emplace(packKey(d), static_cast<long long>(out.doubledCoordinates.size()));
    if (inserted) out.doubledCoordinates.push_back(d);
    return it->second;
  };
  auto existing = [&](const Eigen::Vector3i& d) {
    const auto it = ids.find(packKey(d));
    return it == ids.end() ? -1LL : it->second;
  };
  std::vector<int> leaves;
  for (int c = 0; c < static_cast<int>(cells_.size()); ++c)
    if (cells_[static_cast<std::size_t>(c)].firstChild < 0) leaves.push_back(c);
  // Black vertices (cube corners) first, then red ones (cube centres). A corner lies on the
  // boundary of its leaves and a centre inside its own, so one key never names both.
  for (int c : leaves) {
    const Cell& cell = cells_[static_cast<std::size_t>(c)];
    for (int corner = 0; corner < 8; ++corner)
      vertex(cell.corner + size(cell) * Eigen::Vector3i(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1));
  }
  for (int c : leaves) {
    const Cell& cell = cells_[static_cast<std::size_t>(c)];
    vertex(cell.corner + Eigen::Vector3i::Constant(size(cell) / 2));
  }
  auto emit = [&](const std::array<long long, 4>& tet, bool plain, int ownerA, int ownerB) {
    out.tetrahedra.push_back(tet);
    out.plain.push_back(plain ? 1 : 0);
    out.owners.push_back({ownerA, ownerB});
  };
  auto required = [&](const Eigen::Vector3i& d) {
    const long long id = existing(d);
    if (id < 0) throw Error("stuffIsosurface: internal error: graded lattice is not balanced");
    return id;
  };
  for (int c : leaves) {
    const Cell& cell = cells_[static_cast<std::size_t>(c)];
    const int s = size(cell);
    const Eigen::Vector3i centre = cell.corner + Eigen::Vector3i::Constant(s / 2);
    const long long red = existing(centre);
    for (int a = 0; a < 3; ++a) {
      for (int side : {-1, 1}) {
        Eigen::Vector3i probe = centre;
        probe[a] = side > 0 ? cell.corner[a] + s : cell.corner[a] - 1;
        const int n = locate(probe);
        if (n < 0) continue;  // the domain's boundary: outside the solid by construction
        const Cell& neighbour = cells_[static_cast<std::size_t>(n)];
        // The face's corners in cyclic order.
        const int b = (a + 1) % 3, d = (a + 2) % 3;
        std::array<Eigen::Vector3i, 4> square;
        const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        for (int q = 0; q < 4; ++q) {
          square[static_cast<std::size_t>(q)] = cell.corner;
          square[static_cast<std::size_t>(q)][a] = side > 0 ? cell.corner[a] + s : cell.corner[a];
          square[static_cast<std::size_t>(q)][b] += uv[q][0] * s;
          square[static_cast<std::size_t>(q)][d] += uv[q][1] * s;
        }
        if (neighbour.level == cell.level) {
          if (side < 0) continue;  // emitted by the neighbour, whose +a face this is
          const long long otherRed = required(centre + s * Eigen::Vector3i::Unit(a));
          for (int q = 0; q < 4; ++q) {
            const Eigen::Vector3i& u = square[static_cast<std::size_t>(q)];
            const Eigen::Vector3i& v = square[static_cast<std::size_t>((q + 1) % 4)];
            const long long mid = existing((u + v) / 2);
            if (mid < 0) {
              emit({existing(u), existing(v), red, otherRed}, cell.level == 0, c, n);
            } else {
              emit({existing(u), mid, red, otherRed}, false, c, n);
              emit({mid, existing(v), red, otherRed}, false, c, n);
            }
          }
        } else if (neighbour.level < cell.level) {
          // Smaller neighbours: eight tetrahedra at the face's centre and edge midpoints.
          const long long faceCentre = required((square[0] + square[2]) / 2);
          for (int q = 0; q < 4; ++q) {
            const Eigen::Vector3i& u = square[static_cast<std::size_t>(q)];
            const Eigen::Vector3i& v = square[static_cast<std::size_t>((q + 1) % 4)];
            const long long mid = required((u + v) / 2);
            emit({red, faceCentre, existing(u), mid}, false, c, -1);
            emit({red, faceCentre, mid, existing(v)}, false, c, -1);
          }
        } else {
          // A larger neighbour: split by the diagonal through the centre of its face.
          Eigen::Vector3i bigCentre = neighbour.corner + Eigen::Vector3i::Constant(size(neighbour) / 2);
          bigCentre[a] = square[0][a];
          int k = 0;
          while (k < 4 && square[static_cast<std::size_t>(k)] != bigCentre) ++k;
          if (k == 4) throw Error("stuffIsosurface: internal error: graded lattice is not balanced");
          auto at = [&](int q) { return existing(square[static_cast<std::size_t>((k + q) % 4)]); };
          emit({red, at(0), at(1), at(2)}, false, c, n);
          emit({red, at(0), at(2), at(3)}, false, c, n);
        }
      }
    }
  }
  return out;
}

}  // namespace asyncfem::detail
