// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <asyncfem/collision/triangleIntersection.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <cmath>
#include <limits>

namespace asyncfem {
namespace {

using Vector3 = Eigen::Vector3d;
using Triangle = std::array<Vector3, 3>;

/// trianglesIntersect(a, b), checked to give the same answer for every order of each
/// triangle's corners and with the triangles swapped (the exact predicates make the answer
/// independent of the order; 72 evaluations).
bool intersect(const Triangle& a, const Triangle& b) {
  const bool answer = trianglesIntersect(a[0], a[1], a[2], b[0], b[1], b[2]);
  std::array<int, 3> pa{0, 1, 2};
  do {
    std::array<int, 3> pb{0, 1, 2};
    do {
      const Triangle x{a[pa[0]], a[pa[1]], a[pa[2]]}, y{b[pb[0]], b[pb[1]], b[pb[2]]};
      EXPECT_EQ(trianglesIntersect(x[0], x[1], x[2], y[0], y[1], y[2]), answer);
      EXPECT_EQ(trianglesIntersect(y[0], y[1], y[2], x[0], x[1], x[2]), answer);
    } while (std::next_permutation(pb.begin(), pb.end()));
  } while (std::next_permutation(pa.begin(), pa.end()));
  return answer;
}

const Triangle kUnit{Vector3(0, 0, 0), Vector3(1, 0, 0), Vector3(0, 1, 0)};

TEST(TriangleIntersection, ConstructedCases) {
  // Crossing: a vertical triangle pierces the unit triangle's inside.
  EXPECT_TRUE(intersect(kUnit, {Vector3(0.2, 0.2, -1), Vector3(0.3, 0.2, 1), Vector3(0.2, 0.3, 1)}));
  // Disjoint: the same one moved beside it.
  EXPECT_FALSE(intersect(kUnit, {Vector3(1.2, 1.2, -1), Vector3(1.3, 1.2, 1), Vector3(1.2, 1.3, 1)}));
  // Above, parallel.
  EXPECT_FALSE(intersect(kUnit, {Vector3(0, 0, 0.1), Vector3(1, 0, 0.1), Vector3(0, 1, 0.1)}));
  // Touching: a vertex on the face, an edge across an edge, a shared vertex, a shared edge.
  EXPECT_TRUE(intersect(kUnit, {Vector3(0.25, 0.25, 0), Vector3(0.3, 0.2, 1), Vector3(0.2, 0.3, 1)}));
  EXPECT_TRUE(intersect(kUnit, {Vector3(0.5, -0.5, 0), Vector3(0.5, 0.5, 0), Vector3(0.5, 0, 1)}));
  EXPECT_TRUE(intersect(kUnit, {Vector3(1, 0, 0), Vector3(2, 0, 1), Vector3(2, 1, 1)}));
  EXPECT_TRUE(intersect(kUnit, {Vector3(1, 0, 0), Vector3(0, 1, 0), Vector3(1, 1, 1)}));
  // A vertex just off the face (1e-12 below a touching one) does not touch.
  EXPECT_FALSE(intersect(kUnit, {Vector3(0.25, 0.25, 1e-12), Vector3(0.3, 0.2, 1), Vector3(0.2, 0.3, 1)}));
  // Coplanar: overlapping, one inside the other, sharing an edge, apart.
  EXPECT_TRUE(intersect(kUnit, {Vector3(0.5, 0.5, 0), Vector3(-0.5, 0.2, 0), Vector3(0.2, -0.5, 0)}));
  EXPECT_TRUE(intersect(kUnit, {Vector3(0.1, 0.1, 0), Vector3(0.2, 0.1, 0), Vector3(0.1, 0.2, 0)}));
  EXPECT_TRUE(intersect(kUnit, {Vector3(1, 0, 0), Vector3(0, 1, 0), Vector3(1, 1, 0)}));
  EXPECT_FALSE(intersect(kUnit, {Vector3(0.6, 0.6, 0), Vector3(1, 0.6, 0), Vector3(0.6, 1, 0)}));
  // Degenerate: a zero-area triangle (a segment) through the face, and one beside it.
  EXPECT_TRUE(intersect(kUnit, {Vector3(0.2, 0.2, -1), Vector3(0.2, 0.2, 1), Vector3(0.2, 0.2, 0.5)}));
  EXPECT_FALSE(intersect(kUnit, {Vector3(2, 2, -1), Vector3(2, 2, 1), Vector3(2, 2, 0.5)}));
}

TEST(TriangleIntersection, DecidesExactlyWhereFloatingPointCannot) {
  // A lies in the plane x = y, far from the origin of its first corner, so that differences
  // to that corner round away one unit in the last place of 18.
  const Triangle a{Vector3(-1000, -1000, 0), Vector3(1000, 1000, 0), Vector3(-1000, -1000, 10)};
  const double justAbove = std::nextafter(18.0, 19.0);
  const Triangle touching{Vector3(18, 18, 1), Vector3(23, 13, 1), Vector3(23, 13, 2)};
  const Triangle apart{Vector3(justAbove, 18, 1), Vector3(23, 13, 1), Vector3(23, 13, 2)};
  EXPECT_TRUE(intersect(a, touching));
  EXPECT_FALSE(intersect(a, apart));
  // Negative control: the plain floating-point orientation of the `apart` vertex against A
  // is zero, i.e. it would call the two triangles touching.
  const Vector3 u = a[1] - a[0], v = a[2] - a[0], w = apart[0] - a[0];
  EXPECT_EQ(u.dot(v.cross(w)), 0.0);
}

TEST(TriangleIntersection, CountsPairsBetweenAndWithinSurfaces) {
  BoxMeshSpec spec;
  spec.cells = Eigen::Vector3i(2, 2, 2);
  const TetMesh mesh = makeBoxMesh(spec);
  const CollisionSurface surface = boundarySurface(mesh);
  const Eigen::Matrix3Xd& rest = mesh.restPositions();
  // A closed surface at rest has no intersecting non-adjacent triangles.
  EXPECT_TRUE(selfIntersectingTrianglePairs(surface, rest).empty());
  // A copy moved 0.5 along x cuts the box's faces: the pairs found are exactly those the
  // brute-force broad phase finds.
  Eigen::Matrix3Xd moved = rest;
  moved.row(0).array() += 0.5;
  const auto pairs = intersectingTrianglePairs(surface, rest, surface, moved);
  EXPECT_FALSE(pairs.empty());
  EXPECT_EQ(pairs, intersectingTrianglePairs(surface, rest, surface, moved, BroadPhaseMethod::BruteForce));
  EXPECT_EQ(pairs, intersectingTrianglePairs(surface, rest, surface, moved, BroadPhaseMethod::DynamicTree));
  // Moved 2 along x the copies are apart; moved exactly 1 they share the face x = 1 (touch).
  moved = rest;
  moved.row(0).array() += 2.0;
  EXPECT_TRUE(intersectingTrianglePairs(surface, rest, surface, moved).empty());
  moved = rest;
  moved.row(0).array() += 1.0;
  EXPECT_FALSE(intersectingTrianglePairs(surface, rest, surface, moved).empty());
  // Pushing one vertex of the top face through the bottom face folds the surface into
  // itself.
  Eigen::Matrix3Xd folded = rest;
  int top = -1;
  for (int v = 0; v < mesh.numVertices(); ++v)
    if (std::abs(rest(0, v) - 0.5) < 1e-12 && std::abs(rest(1, v) - 0.5) < 1e-12 && rest(2, v) == 1.0) top = v;
  ASSERT_GE(top, 0);
  folded(2, top) = -0.5;
  EXPECT_FALSE(selfIntersectingTrianglePairs(surface, folded).empty());
  EXPECT_THROW(selfIntersectingTrianglePairs(surface, Eigen::Matrix3Xd::Zero(3, 1)), ValidationError);
}

}  // namespace
}  // namespace asyncfem
