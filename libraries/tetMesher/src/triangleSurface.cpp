// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/triangleSurface.hpp>
#include <cmath>
#include <map>
#include <sstream>
#include <unordered_map>
#include <utility>

namespace asyncfem {

namespace {

std::string describeEdge(const TriangleSurface& surface, int a, int b) {
  std::ostringstream out;
  out.precision(6);
  auto point = [&](int v) {
    const Eigen::Vector3d x = surface.vertices.col(v);
    out << "(" << x.x() << ", " << x.y() << ", " << x.z() << ")";
  };
  out << "edge ";
  point(a);
  out << " - ";
  point(b);
  return out.str();
}

struct CellHash {
  std::size_t operator()(const std::array<long long, 3>& c) const {
    return static_cast<std::size_t>(c[0] * 73856093LL ^ c[1] * 19349663LL ^ c[2] * 83492791LL);
  }
};

}  // namespace

Eigen::AlignedBox3d TriangleSurface::bounds() const {
  Eigen::AlignedBox3d box;
  for (int t = 0; t < numTriangles(); ++t)
    for (int c = 0; c < 3; ++c) box.extend(vertices.col(triangles(c, t)));
  return box;
}

int weldVertices(TriangleSurface& surface, double tolerance) {
  const int n = surface.numVertices();
  std::vector<int> representative(static_cast<std::size_t>(n));
  std::vector<int> kept;  // input ids of the kept vertices, in order
  const double cell = tolerance > 0.0 ? tolerance : 1.0;
  std::unordered_map<std::array<long long, 3>, std::vector<int>, CellHash> grid;  // cell -> kept output ids
  for (int v = 0; v < n; ++v) {
    const Eigen::Vector3d x = surface.vertices.col(v);
    if (!x.allFinite()) throw ValidationError("weldVertices: vertex " + std::to_string(v) + " is not finite");
    std::array<long long, 3> key{};
    for (int a = 0; a < 3; ++a) key[static_cast<std::size_t>(a)] = static_cast<long long>(std::floor(x[a] / cell));
    int match = -1;
    for (int dz = -1; dz <= 1 && match < 0; ++dz)
      for (int dy = -1; dy <= 1 && match < 0; ++dy)
        for (int dx = -1; dx <= 1 && match < 0; ++dx) {
          const auto it = grid.find({key[0] + dx, key[1] + dy, key[2] + dz});
          if (it == grid.end()) continue;
          for (int candidate : it->second) {
            const double gap = (surface.vertices.col(kept[static_cast<std::size_t>(candidate)]) - x).norm();
            if (gap <= tolerance) {
              match = candidate;
              break;
            }
          }
        }
    if (match < 0) {
      match = static_cast<int>(kept.size());
      kept.push_back(v);
      grid[key].push_back(match);
    }
    representative[static_cast<std::size_t>(v)] = match;
  }
  Eigen::Matrix3Xd vertices(3, static_cast<Eigen::Index>(kept.size()));
  for (std::size_t i = 0; i < kept.size(); ++i)
    vertices.col(static_cast<Eigen::Index>(i)) = surface.vertices.col(kept[i]);
  std::vector<int> keep;
  for (int t = 0; t < surface.numTriangles(); ++t) {
    Eigen::Vector3i tri;
    for (int c = 0; c < 3; ++c) {
      const int v = surface.triangles(c, t);
      if (v < 0 || v >= n)
        throw ValidationError("weldVertices: triangle " + std::to_string(t) + " has vertex " + std::to_string(v) +
                              " out of range");
      tri[c] = representative[static_cast<std::size_t>(v)];
    }
    surface.triangles.col(t) = tri;
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
    keep.push_back(t);
  }
  surface.vertices = std::move(vertices);
  if (surface.triangleParts.empty()) surface.triangleParts.assign(static_cast<std::size_t>(surface.numTriangles()), 0);
  selectTriangles(surface, keep);
  if (surface.partNames.empty()) surface.partNames.push_back("surface");
  return n - static_cast<int>(kept.size());
}

void selectTriangles(TriangleSurface& surface, const std::vector<int>& keep) {
  if (surface.inputTriangles.empty()) {
    surface.inputTriangles.resize(static_cast<std::size_t>(surface.numTriangles()));
    for (int t = 0; t < surface.numTriangles(); ++t) surface.inputTriangles[static_cast<std::size_t>(t)] = t;
  }
  auto select = [&keep](std::vector<int>& labels) {
    if (labels.empty()) return;
    std::vector<int> kept;
    kept.reserve(keep.size());
    for (int t : keep) kept.push_back(labels[static_cast<std::size_t>(t)]);
    labels = std::move(kept);
  };
  Eigen::Matrix3Xi triangles(3, static_cast<Eigen::Index>(keep.size()));
  for (std::size_t i = 0; i < keep.size(); ++i)
    triangles.col(static_cast<Eigen::Index>(i)) = surface.triangles.col(keep[i]);
  surface.triangles = std::move(triangles);
  select(surface.triangleParts);
  select(surface.triangleMaterials);
  select(surface.triangleGroups);
  select(surface.inputTriangles);
}

int inputTriangleIndex(const TriangleSurface& surface, int t) {
  return surface.inputTriangles.empty() || t < 0 ? t : surface.inputTriangles[static_cast<std::size_t>(t)];
}

SurfaceTopology surfaceTopology(const TriangleSurface& surface) {
  SurfaceTopology topology;
  std::map<std::pair<int, int>, std::array<int, 2>> edgeUse;  // (lo, hi) -> uses lo->hi, hi->lo
  for (int t = 0; t < surface.numTriangles(); ++t) {
    const Eigen::Vector3d a = surface.vertices.col(surface.triangles(0, t));
    const Eigen::Vector3d b = surface.vertices.col(surface.triangles(1, t));
    const Eigen::Vector3d c = surface.vertices.col(surface.triangles(2, t));
    if ((b - a).cross(c - a).norm() == 0.0) ++topology.degenerateTriangles;
    topology.signedVolume += a.dot(b.cross(c)) / 6.0;
    for (int i = 0; i < 3; ++i) {
      const int u = surface.triangles(i, t), v = surface.triangles((i + 1) % 3, t);
      ++edgeUse[{std::min(u, v), std::max(u, v)}][u < v ? 0 : 1];
    }
  }
  std::string boundaryExample, nonManifoldExample, misorientedExample;
  for (const auto& [edge, use] : edgeUse) {
    const int count = use[0] + use[1];
    if (count == 1) {
      if (topology.boundaryEdges++ == 0) boundaryExample = "open " + describeEdge(surface, edge.first, edge.second);
    } else if (count > 2) {
      if (topology.nonManifoldEdges++ == 0) {
        nonManifoldExample = "non-manifold " + describeEdge(surface, edge.first, edge.second) + " in " +
                             std::to_string(count) + " triangles";
      }
    } else if (use[0] != 1) {
      if (topology.misorientedEdges++ == 0) {
        misorientedExample = "inconsistently oriented " + describeEdge(surface, edge.first, edge.second);
      }
    }
  }
  topology.example = !boundaryExample.empty()      ? boundaryExample
                     : !nonManifoldExample.empty() ? nonManifoldExample
                                                   : misorientedExample;
  return topology;
}

void requireClosedSurface(const TriangleSurface& surface, const std::string& source) {
  if (surface.numTriangles() == 0) throw ValidationError(source + ": the surface has no triangles");
  const SurfaceTopology topology = surfaceTopology(surface);
  if (topology.closed()) return;
  throw ValidationError(source + ": the surface is not closed: " + std::to_string(topology.boundaryEdges) +
                        " open boundary edges, " + std::to_string(topology.nonManifoldEdges) + " non-manifold edges, " +
                        std::to_string(topology.misorientedEdges) +
                        " inconsistently oriented edges after welding (e.g. " + topology.example +
                        "); close the surface, or mesh it with the generalized winding number (--repair), "
                        "which tolerates small holes");
}

void flipOrientation(TriangleSurface& surface) { surface.triangles.row(1).swap(surface.triangles.row(2)); }

}  // namespace asyncfem
