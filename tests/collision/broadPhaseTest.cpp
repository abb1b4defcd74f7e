// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/collision/broadPhase.hpp>
#include <asyncfem/collision/distance.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <random>
#include <string>

namespace asyncfem {
namespace {

constexpr BroadPhaseMethod kFastMethods[] = {BroadPhaseMethod::DynamicTree, BroadPhaseMethod::SpatialHash};

/// Random boxes in [0, 1]^3 of mixed sizes: points, boxes of up to 0.2, a few of up to half
/// the domain and one over all of it (the spatial hash's large-box path), the cases a
/// uniform grid handles worst.
BoxSet randomBoxes(int count, unsigned seed) {
  std::mt19937 generator(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  BoxSet boxes;
  boxes.min.resize(3, count);
  boxes.max.resize(3, count);
  for (int b = 0; b < count; ++b) {
    const double size = b % 10 == 0 ? 0.0 : (b % 37 == 0 ? 0.5 * unit(generator) : 0.2 * unit(generator));
    for (int axis = 0; axis < 3; ++axis) {
      boxes.min(axis, b) = unit(generator);
      boxes.max(axis, b) = boxes.min(axis, b) + size * unit(generator);
    }
  }
  if (count > 1) {  // one box over the whole domain
    boxes.min.col(1).setZero();
    boxes.max.col(1).setOnes();
  }
  return boxes;
}

TEST(BroadPhase, OverlappingBoxesMatchBruteForce) {
  const BoxSet first = randomBoxes(700, 1);
  const BoxSet second = randomBoxes(500, 2);
  const auto expected = overlappingBoxes(first, second, BroadPhaseMethod::BruteForce);
  const auto expectedSelf = overlappingBoxes(first, BroadPhaseMethod::BruteForce);
  ASSERT_GT(expected.size(), 100u);  // the scene has pairs to find
  ASSERT_GT(expectedSelf.size(), 100u);
  for (const BroadPhaseMethod method : kFastMethods) {
    EXPECT_EQ(overlappingBoxes(first, second, method), expected) << static_cast<int>(method);
    EXPECT_EQ(overlappingBoxes(first, method), expectedSelf) << static_cast<int>(method);
  }
  // Touching boxes overlap (closed boxes).
  BoxSet touching;
  touching.min = Eigen::Matrix3Xd::Zero(3, 2);
  touching.max = Eigen::Matrix3Xd::Ones(3, 2);
  touching.min.col(1).x() = 1.0;
  touching.max.col(1).x() = 2.0;
  for (const BroadPhaseMethod method : kFastMethods)
    EXPECT_EQ(overlappingBoxes(touching, method).size(), 1u) << static_cast<int>(method);
}

/// A box mesh of n^3 cells of size `size` at `origin`, its rest positions moved by uniform
/// noise of +-amplitude per coordinate.
struct Body {
  CollisionSurface surface;
  Eigen::Matrix3Xd positions;
};
Body perturbedBox(int cells, const Eigen::Vector3d& origin, double size, double amplitude, unsigned seed) {
  BoxMeshSpec spec;
  spec.origin = origin;
  spec.size = Eigen::Vector3d::Constant(size);
  spec.cells = Eigen::Vector3i::Constant(cells);
  const TetMesh mesh = makeBoxMesh(spec);
  std::mt19937 generator(seed);
  std::uniform_real_distribution<double> noise(-amplitude, amplitude);
  Body body{boundarySurface(mesh), mesh.restPositions()};
  for (Eigen::Index i = 0; i < body.positions.size(); ++i) body.positions.data()[i] += noise(generator);
  return body;
}

Eigen::Vector3d corner(const Body& body, int triangle, int c) {
  return body.positions.col(body.surface.triangles(c, triangle));
}
Eigen::Vector3d edgeEnd(const Body& body, int edge, int c) { return body.positions.col(body.surface.edges(c, edge)); }

/// Pairs farther than dhat by less than this fraction may fall either way with the round-off
/// of the box corners (one addition of dhat / 2), so the exact check leaves them out.
constexpr double kBoundaryFraction = 1e-9;

/// Every vertex-triangle pair of (vertexBody, triangleBody) closer than dhat is a candidate,
/// unless excluded as incident.
void expectVertexTrianglePairsWithinDhatFound(const Body& vertexBody, const Body& triangleBody, double dhat,
                                              const std::vector<VertexTriangleCandidate>& candidates, bool self) {
  int within = 0;
  for (const int v : vertexBody.surface.vertices) {
    for (int t = 0; t < triangleBody.surface.numTriangles(); ++t) {
      if (self && (triangleBody.surface.triangles.col(t).array() == v).any()) continue;
      const double d2 = pointTriangleDistanceSquared(vertexBody.positions.col(v), corner(triangleBody, t, 0),
                                                     corner(triangleBody, t, 1), corner(triangleBody, t, 2));
      if (d2 >= std::pow(dhat * (1.0 - kBoundaryFraction), 2)) continue;
      ++within;
      EXPECT_TRUE(std::binary_search(candidates.begin(), candidates.end(), VertexTriangleCandidate{v, t}))
          << "vertex " << v << " triangle " << t << " at distance " << std::sqrt(d2) << " missed";
    }
  }
  EXPECT_GT(within, 0) << "the scene has no pair within dhat: the check would pass vacuously";
}

void expectEdgePairsWithinDhatFound(const Body& first, const Body& second, double dhat,
                                    const std::vector<EdgeEdgeCandidate>& candidates, bool self) {
  int within = 0;
  for (int a = 0; a < first.surface.numEdges(); ++a) {
    for (int b = self ? a + 1 : 0; b < second.surface.numEdges(); ++b) {
      if (self && (first.surface.edges.col(a).array() == second.surface.edges(0, b) ||
                   first.surface.edges.col(a).array() == second.surface.edges(1, b))
                      .any())
        continue;
      const double d2 = edgeEdgeDistanceSquared(edgeEnd(first, a, 0), edgeEnd(first, a, 1), edgeEnd(second, b, 0),
                                                edgeEnd(second, b, 1));
      if (d2 >= std::pow(dhat * (1.0 - kBoundaryFraction), 2)) continue;
      ++within;
      EXPECT_TRUE(std::binary_search(candidates.begin(), candidates.end(), EdgeEdgeCandidate{a, b}))
          << "edges " << a << ", " << b << " at distance " << std::sqrt(d2) << " missed";
    }
  }
  EXPECT_GT(within, 0) << "the scene has no pair within dhat: the check would pass vacuously";
}

/// Brute force finds every pair between the two surfaces within dhat, and the fast methods
/// return exactly brute force's candidates.
void expectTwoSurfaceCandidatesComplete(const Body& first, const Body& second, double dhat) {
  const ContactCandidates expected = findContactCandidates(first.surface, first.positions, second.surface,
                                                           second.positions, dhat, BroadPhaseMethod::BruteForce);
  expectVertexTrianglePairsWithinDhatFound(first, second, dhat, expected.firstVerticesSecondTriangles, false);
  expectVertexTrianglePairsWithinDhatFound(second, first, dhat, expected.secondVerticesFirstTriangles, false);
  expectEdgePairsWithinDhatFound(first, second, dhat, expected.edgeEdge, false);
  for (const BroadPhaseMethod method : kFastMethods) {
    const ContactCandidates found =
        findContactCandidates(first.surface, first.positions, second.surface, second.positions, dhat, method);
    EXPECT_EQ(found.firstVerticesSecondTriangles, expected.firstVerticesSecondTriangles);
    EXPECT_EQ(found.secondVerticesFirstTriangles, expected.secondVerticesFirstTriangles);
    EXPECT_EQ(found.edgeEdge, expected.edgeEdge);
  }
}

// Tiny boxes spread over a large domain: a grid of about 2^60 cells, past the radix sort's
// key range, and few pairs among many boxes, past the counting sort's index range; both
// fall back to comparison sorts, which must give the same pairs in the same order.
TEST(BroadPhase, SparseScenesTakeTheComparisonSortsAndMatchBruteForce) {
  std::mt19937 generator(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int count = 6000;
  BoxSet boxes;
  boxes.min.resize(3, count);
  boxes.max.resize(3, count);
  for (int b = 0; b < count; ++b) {
    const Eigen::Vector3d low = b % 60 == 59 ? Eigen::Vector3d(boxes.min.col(b - 1).array() + 5e-8)
                                             : Eigen::Vector3d(unit(generator), unit(generator), unit(generator));
    boxes.min.col(b) = low;
    boxes.max.col(b) = low.array() + 1e-7;
  }
  const auto expected = overlappingBoxes(boxes, BroadPhaseMethod::BruteForce);
  ASSERT_GE(expected.size(), 100u);                           // every 60th box overlaps its predecessor
  ASSERT_LT(8 * expected.size() + 4096, std::size_t{count});  // the counting sort's range is exceeded
  for (const BroadPhaseMethod method : kFastMethods)
    EXPECT_EQ(overlappingBoxes(boxes, method), expected) << static_cast<int>(method);
  BoxSet first, second;
  first.min = boxes.min.leftCols(count / 2);
  first.max = boxes.max.leftCols(count / 2);
  second.min = boxes.min.rightCols(count / 2);
  second.max = boxes.max.rightCols(count / 2);
  const auto expectedPairs = overlappingBoxes(first, second, BroadPhaseMethod::BruteForce);
  for (const BroadPhaseMethod method : kFastMethods)
    EXPECT_EQ(overlappingBoxes(first, second, method), expectedPairs) << static_cast<int>(method);
}

TEST(BroadPhase, BodyAgainstObstacleFindsEveryPairWithinDhat) {
  // A perturbed box resting 0.01 above a wavy triangulated floor (the static obstacle).
  const Body body = perturbedBox(4, {0.0, 0.01, 0.0}, 1.0, 0.02, 3);
  const int n = 12;
  Body floor;
  floor.positions.resize(3, (n + 1) * (n + 1));
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      floor.positions.col(j * (n + 1) + i) =
          Eigen::Vector3d(-0.2 + 1.4 * i / n, 0.01 * std::sin(7.0 * i + 3.0 * j), -0.2 + 1.4 * j / n);
  Eigen::Matrix3Xi triangles(3, 2 * n * n);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int v = j * (n + 1) + i;
      triangles.col(2 * (j * n + i)) << v, v + n + 1, v + 1;
      triangles.col(2 * (j * n + i) + 1) << v + 1, v + n + 1, v + n + 2;
    }
  }
  floor.surface = triangleSurface(triangles, static_cast<int>(floor.positions.cols()));
  expectTwoSurfaceCandidatesComplete(body, floor, 0.03);
}

TEST(BroadPhase, BodyAgainstBodyFindsEveryPairWithinDhat) {
  const Body first = perturbedBox(3, {0.0, 0.0, 0.0}, 1.0, 0.05, 4);
  const Body second = perturbedBox(4, {0.98, 0.3, 0.2}, 0.8, 0.05, 5);
  expectTwoSurfaceCandidatesComplete(first, second, 0.05);
}

TEST(BroadPhase, SelfContactFindsEveryPairWithinDhatAndExcludesNeighbours) {
  // Noise of a third of a cell brings non-adjacent surface primitives within dhat.
  const Body body = perturbedBox(4, Eigen::Vector3d::Zero(), 1.0, 0.08, 6);
  const double dhat = 0.1;
  const ContactCandidates expected =
      findSelfContactCandidates(body.surface, body.positions, dhat, BroadPhaseMethod::BruteForce);
  EXPECT_TRUE(expected.secondVerticesFirstTriangles.empty());
  expectVertexTrianglePairsWithinDhatFound(body, body, dhat, expected.firstVerticesSecondTriangles, true);
  expectEdgePairsWithinDhatFound(body, body, dhat, expected.edgeEdge, true);
  for (const VertexTriangleCandidate& c : expected.firstVerticesSecondTriangles)
    EXPECT_FALSE((body.surface.triangles.col(c.triangle).array() == c.vertex).any()) << "incident pair kept";
  for (const EdgeEdgeCandidate& c : expected.edgeEdge) {
    EXPECT_LT(c.first, c.second);
    const Eigen::Vector2i a = body.surface.edges.col(c.first), b = body.surface.edges.col(c.second);
    EXPECT_FALSE(a[0] == b[0] || a[0] == b[1] || a[1] == b[0] || a[1] == b[1]) << "adjacent edges kept";
  }
  for (const BroadPhaseMethod method : kFastMethods) {
    const ContactCandidates found = findSelfContactCandidates(body.surface, body.positions, dhat, method);
    EXPECT_EQ(found.firstVerticesSecondTriangles, expected.firstVerticesSecondTriangles);
    EXPECT_EQ(found.edgeEdge, expected.edgeEdge);
  }
}

TEST(BroadPhase, BadInputNamesWhatIsWrong) {
  const Body body = perturbedBox(1, Eigen::Vector3d::Zero(), 1.0, 0.0, 7);
  EXPECT_THROW(findSelfContactCandidates(body.surface, body.positions, -1.0), ValidationError);
  EXPECT_THROW(findSelfContactCandidates(body.surface, Eigen::Matrix3Xd::Zero(3, 2), 0.1), ValidationError);
  BoxSet boxes = randomBoxes(5, 8);
  boxes.min(1, 3) = boxes.max(1, 3) + 1.0;
  try {
    overlappingBoxes(boxes);
    FAIL() << "expected ValidationError";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("box 3"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace asyncfem
