// SPDX-License-Identifier: BSD-3-Clause
// Small triangle surfaces for the tetMesher tests, built in code (and written as OBJ).
#pragma once

#include <array>
#include <asyncfem/tetMesher/triangleSurface.hpp>
#include <cmath>
#include <numbers>
#include <sstream>
#include <string>

namespace asyncfem::test {

/// Axis-aligned cube [origin, origin + size]^3 with every face carrying its own four
/// vertices (24 in all), as exporters write cubes with per-face normals; outward, CCW.
inline TriangleSurface splitCube(const Eigen::Vector3d& origin, double size) {
  // Each face: four corners (unit cube) counter-clockwise seen from outside.
  static constexpr std::array<std::array<std::array<int, 3>, 4>, 6> kFaces{{
      {{{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}}},  // z = 0
      {{{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}},  // z = 1
      {{{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}},  // y = 0
      {{{0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}}},  // y = 1
      {{{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}}},  // x = 0
      {{{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}}},  // x = 1
  }};
  TriangleSurface s;
  s.vertices.resize(3, 24);
  s.triangles.resize(3, 12);
  for (int f = 0; f < 6; ++f) {
    for (int c = 0; c < 4; ++c) {
      const auto& p = kFaces[static_cast<std::size_t>(f)][static_cast<std::size_t>(c)];
      s.vertices.col(4 * f + c) = origin + size * Eigen::Vector3d(p[0], p[1], p[2]);
    }
    s.triangles.col(2 * f) = Eigen::Vector3i(4 * f, 4 * f + 1, 4 * f + 2);
    s.triangles.col(2 * f + 1) = Eigen::Vector3i(4 * f, 4 * f + 2, 4 * f + 3);
  }
  s.triangleParts.assign(12, 0);
  s.partNames = {"cube"};
  return s;
}

/// Closed UV sphere: `slices` around, `stacks` from pole to pole, shared pole vertices.
inline TriangleSurface uvSphere(const Eigen::Vector3d& centre, double radius, int slices, int stacks) {
  TriangleSurface s;
  const int ring = slices;
  const int numVertices = 2 + (stacks - 1) * ring;
  s.vertices.resize(3, numVertices);
  s.vertices.col(0) = centre + Eigen::Vector3d(0, 0, radius);
  s.vertices.col(numVertices - 1) = centre - Eigen::Vector3d(0, 0, radius);
  for (int i = 1; i < stacks; ++i) {
    const double theta = std::numbers::pi * i / stacks;
    for (int j = 0; j < ring; ++j) {
      const double phi = 2.0 * std::numbers::pi * j / ring;
      s.vertices.col(1 + (i - 1) * ring + j) =
          centre +
          radius * Eigen::Vector3d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
    }
  }
  std::vector<Eigen::Vector3i> triangles;
  auto at = [&](int i, int j) { return 1 + (i - 1) * ring + (j % ring); };
  for (int j = 0; j < ring; ++j) triangles.emplace_back(0, at(1, j), at(1, j + 1));
  for (int i = 1; i + 1 < stacks; ++i)
    for (int j = 0; j < ring; ++j) {
      triangles.emplace_back(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      triangles.emplace_back(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
  for (int j = 0; j < ring; ++j) triangles.emplace_back(numVertices - 1, at(stacks - 1, j + 1), at(stacks - 1, j));
  s.triangles.resize(3, static_cast<Eigen::Index>(triangles.size()));
  for (std::size_t t = 0; t < triangles.size(); ++t) s.triangles.col(static_cast<Eigen::Index>(t)) = triangles[t];
  s.triangleParts.assign(triangles.size(), 0);
  s.partNames = {"sphere"};
  return s;
}

/// a and b as one surface with parts nameA and nameB.
inline TriangleSurface concatenate(const TriangleSurface& a, const std::string& nameA, const TriangleSurface& b,
                                   const std::string& nameB) {
  TriangleSurface s;
  s.vertices.resize(3, a.numVertices() + b.numVertices());
  s.vertices << a.vertices, b.vertices;
  s.triangles.resize(3, a.numTriangles() + b.numTriangles());
  s.triangles << a.triangles, (b.triangles.array() + a.numVertices()).matrix();
  s.triangleParts.assign(static_cast<std::size_t>(a.numTriangles()), 0);
  s.triangleParts.insert(s.triangleParts.end(), static_cast<std::size_t>(b.numTriangles()), 1);
  s.partNames = {nameA, nameB};
  return s;
}

/// Wavefront OBJ text of a surface, one `o NAME` object per part (1-based indices).
inline std::string toObj(const TriangleSurface& s) {
  std::ostringstream out;
  out.precision(17);
  for (int v = 0; v < s.numVertices(); ++v)
    out << "v " << s.vertices(0, v) << " " << s.vertices(1, v) << " " << s.vertices(2, v) << "\n";
  for (std::size_t p = 0; p < s.partNames.size(); ++p) {
    out << "o " << s.partNames[p] << "\n";
    for (int t = 0; t < s.numTriangles(); ++t) {
      if (s.triangleParts[static_cast<std::size_t>(t)] != static_cast<int>(p)) continue;
      out << "f " << s.triangles(0, t) + 1 << " " << s.triangles(1, t) + 1 << " " << s.triangles(2, t) + 1 << "\n";
    }
  }
  return out.str();
}

}  // namespace asyncfem::test
