// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/collision/broadPhase.hpp>
#include <asyncfem/core/error.hpp>
#include <cmath>
#include <detail/boxPairs.hpp>
#include <string>

namespace asyncfem {

namespace {

using detail::BoxPairs;

void checkBoxes(const BoxSet& boxes, const char* which) {
  if (boxes.min.cols() != boxes.max.cols()) {
    throw ValidationError(std::string("overlappingBoxes: ") + which + " box set has " +
                          std::to_string(boxes.min.cols()) + " min corners and " + std::to_string(boxes.max.cols()) +
                          " max corners");
  }
  for (int b = 0; b < boxes.size(); ++b) {
    if (!boxes.min.col(b).allFinite() || !boxes.max.col(b).allFinite() ||
        (boxes.min.col(b).array() > boxes.max.col(b).array()).any()) {
      throw ValidationError(std::string("overlappingBoxes: box ") + std::to_string(b) + " of the " + which +
                            " set is not finite or has min > max");
    }
  }
}

BoxPairs bruteForcePairs(const BoxSet& first, const BoxSet& second) {
  BoxPairs pairs;
  for (int i = 0; i < first.size(); ++i)
    for (int j = 0; j < second.size(); ++j)
      if (detail::boxesOverlap(first, i, second, j)) pairs.emplace_back(i, j);
  return pairs;
}

BoxPairs bruteForceSelfPairs(const BoxSet& boxes) {
  BoxPairs pairs;
  for (int i = 0; i < boxes.size(); ++i)
    for (int j = i + 1; j < boxes.size(); ++j)
      if (detail::boxesOverlap(boxes, i, boxes, j)) pairs.emplace_back(i, j);
  return pairs;
}

/// The pairs in ascending (first, second) order: two stable counting sorts, by second and
/// then by first, when the index ranges are within a small multiple of the pair count (a
/// broad phase's usual case, linear where std::sort is n log n); std::sort otherwise.
BoxPairs sorted(BoxPairs pairs) {
  int firstCount = 0, secondCount = 0;
  for (const auto& [i, j] : pairs) {
    firstCount = std::max(firstCount, i + 1);
    secondCount = std::max(secondCount, j + 1);
  }
  const std::size_t budget = (8 * pairs.size()) + 4096;
  if (static_cast<std::size_t>(firstCount) > budget || static_cast<std::size_t>(secondCount) > budget) {
    std::sort(pairs.begin(), pairs.end());
    return pairs;
  }
  BoxPairs buffer(pairs.size());
  std::vector<std::size_t> start;
  const auto countingSort = [&](int count, auto digit) {
    start.assign(static_cast<std::size_t>(count) + 1, 0);
    for (const auto& pair : pairs) ++start[static_cast<std::size_t>(digit(pair)) + 1];
    for (std::size_t d = 0; d < static_cast<std::size_t>(count); ++d) start[d + 1] += start[d];
    for (const auto& pair : pairs) buffer[start[static_cast<std::size_t>(digit(pair))]++] = pair;
    pairs.swap(buffer);
  };
  countingSort(secondCount, [](const std::pair<int, int>& pair) { return pair.second; });
  countingSort(firstCount, [](const std::pair<int, int>& pair) { return pair.first; });
  return pairs;
}

/// Boxes of primitives with `corners` vertices each (columns of `primitives`, mesh ids).
template <int Corners>
BoxSet primitiveBoxes(const Eigen::Matrix<int, Corners, Eigen::Dynamic>& primitives, const Eigen::Matrix3Xd& positions,
                      double margin) {
  BoxSet boxes;
  boxes.min.resize(3, primitives.cols());
  boxes.max.resize(3, primitives.cols());
  for (Eigen::Index p = 0; p < primitives.cols(); ++p) {
    Eigen::Vector3d low = positions.col(primitives(0, p));
    Eigen::Vector3d high = low;
    for (int c = 1; c < Corners; ++c) {
      low = low.cwiseMin(positions.col(primitives(c, p)));
      high = high.cwiseMax(positions.col(primitives(c, p)));
    }
    boxes.min.col(p) = low.array() - margin;
    boxes.max.col(p) = high.array() + margin;
  }
  return boxes;
}

void checkDistance(double dhat, const char* what) {
  if (!std::isfinite(dhat) || dhat < 0.0)
    throw ValidationError(std::string(what) + ": dhat " + std::to_string(dhat) + " is not a finite length >= 0");
}

/// Vertex-triangle candidates from pairs (index into surface.vertices, triangle).
std::vector<VertexTriangleCandidate> vertexTriangleCandidates(const BoxPairs& pairs, const CollisionSurface& vertices,
                                                              const CollisionSurface* excludeIncident) {
  std::vector<VertexTriangleCandidate> candidates;
  candidates.reserve(pairs.size());
  for (const auto& [v, t] : pairs) {
    const int vertex = vertices.vertices[static_cast<std::size_t>(v)];
    if (excludeIncident != nullptr && (excludeIncident->triangles.col(t).array() == vertex).any()) continue;
    candidates.push_back({vertex, t});
  }
  std::sort(candidates.begin(), candidates.end());
  return candidates;
}

}  // namespace

std::vector<std::pair<int, int>> overlappingBoxes(const BoxSet& first, const BoxSet& second, BroadPhaseMethod method) {
  checkBoxes(first, "first");
  checkBoxes(second, "second");
  switch (method) {
    case BroadPhaseMethod::DynamicTree:
      return sorted(detail::dynamicTreePairs(first, second));
    case BroadPhaseMethod::SpatialHash:
      return sorted(detail::spatialHashPairs(first, second));
    case BroadPhaseMethod::BruteForce:
      break;
  }
  return bruteForcePairs(first, second);
}

std::vector<std::pair<int, int>> overlappingBoxes(const BoxSet& boxes, BroadPhaseMethod method) {
  checkBoxes(boxes, "only");
  switch (method) {
    case BroadPhaseMethod::DynamicTree:
      return sorted(detail::dynamicTreeSelfPairs(boxes));
    case BroadPhaseMethod::SpatialHash:
      return sorted(detail::spatialHashSelfPairs(boxes));
    case BroadPhaseMethod::BruteForce:
      break;
  }
  return bruteForceSelfPairs(boxes);
}

BoxSet vertexBoxes(const CollisionSurface& surface, const Eigen::Matrix3Xd& positions, double margin) {
  const Eigen::Map<const Eigen::Matrix<int, 1, Eigen::Dynamic>> ids(surface.vertices.data(), 1,
                                                                    surface.numSurfaceVertices());
  return primitiveBoxes<1>(ids, positions, margin);
}

BoxSet edgeBoxes(const CollisionSurface& surface, const Eigen::Matrix3Xd& positions, double margin) {
  return primitiveBoxes<2>(surface.edges, positions, margin);
}

BoxSet triangleBoxes(const CollisionSurface& surface, const Eigen::Matrix3Xd& positions, double margin) {
  return primitiveBoxes<3>(surface.triangles, positions, margin);
}

ContactCandidates findContactCandidates(const CollisionSurface& first, const Eigen::Matrix3Xd& firstPositions,
                                        const CollisionSurface& second, const Eigen::Matrix3Xd& secondPositions,
                                        double dhat, BroadPhaseMethod method) {
  checkDistance(dhat, "findContactCandidates");
  checkPositions(first, firstPositions, "findContactCandidates (first surface)");
  checkPositions(second, secondPositions, "findContactCandidates (second surface)");
  const double margin = 0.5 * dhat;
  ContactCandidates candidates;
  candidates.firstVerticesSecondTriangles =
      vertexTriangleCandidates(overlappingBoxes(vertexBoxes(first, firstPositions, margin),
                                                triangleBoxes(second, secondPositions, margin), method),
                               first, nullptr);
  candidates.secondVerticesFirstTriangles =
      vertexTriangleCandidates(overlappingBoxes(vertexBoxes(second, secondPositions, margin),
                                                triangleBoxes(first, firstPositions, margin), method),
                               second, nullptr);
  for (const auto& [a, b] :
       overlappingBoxes(edgeBoxes(first, firstPositions, margin), edgeBoxes(second, secondPositions, margin), method))
    candidates.edgeEdge.push_back({a, b});
  return candidates;
}

ContactCandidates findSelfContactCandidates(const CollisionSurface& surface, const Eigen::Matrix3Xd& positions,
                                            double dhat, BroadPhaseMethod method) {
  checkDistance(dhat, "findSelfContactCandidates");
  checkPositions(surface, positions, "findSelfContactCandidates");
  const double margin = 0.5 * dhat;
  ContactCandidates candidates;
  candidates.firstVerticesSecondTriangles = vertexTriangleCandidates(
      overlappingBoxes(vertexBoxes(surface, positions, margin), triangleBoxes(surface, positions, margin), method),
      surface, &surface);
  for (const auto& [a, b] : overlappingBoxes(edgeBoxes(surface, positions, margin), method)) {
    const Eigen::Vector2i edgeA = surface.edges.col(a);
    const Eigen::Vector2i edgeB = surface.edges.col(b);
    const bool shareVertex =
        edgeA[0] == edgeB[0] || edgeA[0] == edgeB[1] || edgeA[1] == edgeB[0] || edgeA[1] == edgeB[1];
    if (!shareVertex) candidates.edgeEdge.push_back({a, b});
  }
  return candidates;
}

}  // namespace asyncfem
