// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/meshChecks.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <sstream>
#include <utility>
#include <vector>

namespace asyncfem {

namespace {

std::string describePoint(const Eigen::Vector3d& x) {
  std::ostringstream out;
  out.precision(6);
  out << "(" << x.x() << ", " << x.y() << ", " << x.z() << ")";
  return out.str();
}

int find(std::vector<int>& parent, int x) {
  while (parent[static_cast<std::size_t>(x)] != x) {
    parent[static_cast<std::size_t>(x)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
    x = parent[static_cast<std::size_t>(x)];
  }
  return x;
}

}  // namespace

MeshQuality meshQuality(const TetMesh& mesh) {
  MeshQuality quality;
  if (mesh.numElements() == 0) return quality;
  const double toDegrees = 180.0 / std::numbers::pi;
  quality.minDihedralDegrees = std::numeric_limits<double>::infinity();
  for (const ElementQuality& q : elementQualities(mesh)) {
    quality.minDihedralDegrees = std::min(quality.minDihedralDegrees, q.minDihedralAngle * toDegrees);
    quality.maxDihedralDegrees = std::max(quality.maxDihedralDegrees, q.maxDihedralAngle * toDegrees);
    quality.worstAspectRatio = std::max(quality.worstAspectRatio, q.aspectRatio);
  }
  return quality;
}

namespace {

/// Records the first problem found; later ones only count.
void note(MeshCheckReport& report, const std::string& problem) {
  if (report.firstProblem.empty()) report.firstProblem = problem;
}

/// Element volumes, degenerate and inverted elements, unused vertices.
void checkElements(const TetMesh& mesh, MeshCheckReport& report) {
  const double toDegrees = 180.0 / std::numbers::pi;
  for (int e = 0; e < mesh.numElements(); ++e) {
    const double volume = signedElementVolume(mesh, e);
    const Eigen::Matrix<double, 3, 4> x = mesh.elementRestPositions(e);
    double meanEdge = 0.0;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) meanEdge += (x.col(a) - x.col(b)).norm() / 6.0;
    const ElementQuality q = elementQuality(mesh, e);
    report.elementVolume += volume;
    if (std::abs(volume) <= 1e-10 * meanEdge * meanEdge * meanEdge || q.minDihedralAngle * toDegrees < 0.01) {
      ++report.degenerateElements;
      note(report, "element " + std::to_string(e) + " is degenerate (volume " + std::to_string(volume) +
                       ", min dihedral angle " + std::to_string(q.minDihedralAngle * toDegrees) + " degrees) near " +
                       describePoint(x.rowwise().mean()));
    } else if (volume < 0.0) {
      ++report.invertedElements;
      note(report, "element " + std::to_string(e) + " is inverted near " + describePoint(x.rowwise().mean()));
    }
  }
  report.unusedVertices = static_cast<int>(unusedVertices(mesh).size());
  if (report.unusedVertices > 0) {
    note(report, std::to_string(report.unusedVertices) + " vertices are used by no element, e.g. vertex " +
                     std::to_string(unusedVertices(mesh).front()));
  }
}

/// Boundary triangles, the volume they enclose, and how each boundary edge is traversed.
void checkBoundary(const TetMesh& mesh, MeshCheckReport& report) {
  const std::vector<std::array<int, 3>> boundary = boundaryTriangles(mesh);
  report.boundaryTriangles = static_cast<int>(boundary.size());
  // Each undirected boundary edge: how often it is traversed a->b (a < b) and b->a.
  std::map<std::pair<int, int>, std::array<int, 2>> edgeUse;
  for (const auto& t : boundary) {
    for (int i = 0; i < 3; ++i) {
      const int a = t[static_cast<std::size_t>(i)];
      const int b = t[static_cast<std::size_t>((i + 1) % 3)];
      auto& use = edgeUse[{std::min(a, b), std::max(a, b)}];
      ++use[a < b ? 0 : 1];
    }
    const Eigen::Vector3d xa = mesh.restPosition(t[0]), xb = mesh.restPosition(t[1]), xc = mesh.restPosition(t[2]);
    report.boundaryVolume += xa.dot(xb.cross(xc)) / 6.0;
  }
  for (const auto& [edge, use] : edgeUse) {
    const int count = use[0] + use[1];
    const std::string where = "boundary edge " + describePoint(mesh.restPosition(edge.first)) + " - " +
                              describePoint(mesh.restPosition(edge.second));
    if (count == 1) {
      ++report.openBoundaryEdges;
      note(report, where + " belongs to one boundary triangle (open boundary)");
    } else if (count > 2 && use[0] == use[1]) {
      // Two (or more) sheets of the boundary touching along this edge: the solid is pinched
      // there, which the elements represent correctly (every sheet is closed and outward).
      ++report.pinchedBoundaryEdges;
    } else if (count > 2) {
      ++report.nonManifoldBoundaryEdges;
      note(report, where + " belongs to " + std::to_string(count) + " boundary triangles (non-manifold)");
    } else if (use[0] != 1) {
      ++report.misorientedBoundaryEdges;
      note(report, where + ": its two boundary triangles are oriented inconsistently");
    }
  }
}

/// Components: union elements that share a face (sorted face keys next to each other).
int countComponents(const TetMesh& mesh) {
  std::vector<int> parent(static_cast<std::size_t>(mesh.numElements()));
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<std::pair<std::array<int, 3>, int>> faces;
  faces.reserve(4 * static_cast<std::size_t>(mesh.numElements()));
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Eigen::Vector4i t = mesh.element(e);
    for (int skip = 0; skip < 4; ++skip) {
      std::array<int, 3> key{};
      int k = 0;
      for (int a = 0; a < 4; ++a)
        if (a != skip) key[static_cast<std::size_t>(k++)] = t[a];
      std::sort(key.begin(), key.end());
      faces.emplace_back(key, e);
    }
  }
  std::sort(faces.begin(), faces.end());
  for (std::size_t i = 1; i < faces.size(); ++i) {
    if (faces[i].first == faces[i - 1].first) {
      parent[static_cast<std::size_t>(find(parent, faces[i].second))] = find(parent, faces[i - 1].second);
    }
  }
  int components = 0;
  for (int e = 0; e < mesh.numElements(); ++e)
    if (find(parent, e) == e) ++components;
  return components;
}

}  // namespace

MeshCheckReport checkTetMesh(const TetMesh& mesh) {
  MeshCheckReport report;
  checkElements(mesh, report);
  checkBoundary(mesh, report);
  const double volumeScale = std::max(std::abs(report.elementVolume), std::numeric_limits<double>::min());
  if (report.firstProblem.empty() && std::abs(report.boundaryVolume - report.elementVolume) > 1e-9 * volumeScale) {
    note(report, "the boundary encloses volume " + std::to_string(report.boundaryVolume) + " but the elements have " +
                     std::to_string(report.elementVolume) + " (boundary not oriented outward)");
  }
  report.components = countComponents(mesh);
  if (mesh.numElements() == 0) note(report, "the mesh has no elements");
  return report;
}

void validateTetMesh(const TetMesh& mesh, const std::string& context) {
  const MeshCheckReport report = checkTetMesh(mesh);
  if (!report.ok()) throw ValidationError(context + ": " + report.firstProblem);
}

}  // namespace asyncfem
