// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <array>
#include <asyncfem/collision/collisionSurface.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <string>
#include <utility>

namespace asyncfem {

CollisionSurface triangleSurface(const Eigen::Matrix3Xi& triangles, int numVertices) {
  if (numVertices < 0) throw ValidationError("triangleSurface: negative vertex count " + std::to_string(numVertices));
  CollisionSurface surface;
  surface.triangles = triangles;
  surface.numMeshVertices = numVertices;
  std::vector<std::pair<int, int>> edges;
  edges.reserve(3 * static_cast<std::size_t>(triangles.cols()));
  std::vector<char> used(static_cast<std::size_t>(numVertices), 0);
  for (int t = 0; t < triangles.cols(); ++t) {
    for (int a = 0; a < 3; ++a) {
      const int v = triangles(a, t);
      if (v < 0 || v >= numVertices) {
        throw ValidationError("triangleSurface: triangle " + std::to_string(t) + " has vertex id " + std::to_string(v) +
                              " outside [0, " + std::to_string(numVertices) + ")");
      }
    }
    if (triangles(0, t) == triangles(1, t) || triangles(1, t) == triangles(2, t) ||
        triangles(0, t) == triangles(2, t)) {
      throw ValidationError("triangleSurface: triangle " + std::to_string(t) + " repeats a vertex (" +
                            std::to_string(triangles(0, t)) + ", " + std::to_string(triangles(1, t)) + ", " +
                            std::to_string(triangles(2, t)) + ")");
    }
    for (int a = 0; a < 3; ++a) {
      const int v = triangles(a, t);
      const int w = triangles((a + 1) % 3, t);
      edges.emplace_back(std::min(v, w), std::max(v, w));
      used[static_cast<std::size_t>(v)] = 1;
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  surface.edges.resize(2, static_cast<Eigen::Index>(edges.size()));
  for (std::size_t e = 0; e < edges.size(); ++e) {
    surface.edges(0, static_cast<Eigen::Index>(e)) = edges[e].first;
    surface.edges(1, static_cast<Eigen::Index>(e)) = edges[e].second;
  }
  for (int v = 0; v < numVertices; ++v)
    if (used[static_cast<std::size_t>(v)]) surface.vertices.push_back(v);
  return surface;
}

CollisionSurface boundarySurface(const TetMesh& mesh) {
  const std::vector<std::array<int, 3>> boundary = boundaryTriangles(mesh);
  Eigen::Matrix3Xi triangles(3, static_cast<Eigen::Index>(boundary.size()));
  for (std::size_t t = 0; t < boundary.size(); ++t)
    for (std::size_t a = 0; a < 3; ++a)
      triangles(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(t)) = boundary[t][a];
  return triangleSurface(triangles, mesh.numVertices());
}

void checkPositions(const CollisionSurface& surface, const Eigen::Matrix3Xd& positions, const char* what) {
  if (positions.cols() != surface.numMeshVertices) {
    throw ValidationError(std::string(what) + ": positions have " + std::to_string(positions.cols()) +
                          " columns, the surface's mesh has " + std::to_string(surface.numMeshVertices) + " vertices");
  }
  for (const int v : surface.vertices) {
    if (!positions.col(v).allFinite())
      throw ValidationError(std::string(what) + ": vertex " + std::to_string(v) + " has a non-finite position");
  }
}

}  // namespace asyncfem
