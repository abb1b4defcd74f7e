// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <array>
#include <asyncfem/collision/triangleIntersection.hpp>
#include <detail/exactPredicates.hpp>

namespace asyncfem {

namespace {

using Vector2 = Eigen::Vector2d;
using Vector3 = Eigen::Vector3d;
using detail::orientation2d;
using detail::orientation3d;

/// Drops coordinate `axis` (exact).
Vector2 project(const Vector3& x, int axis) {
  return axis == 0 ? Vector2(x.y(), x.z()) : (axis == 1 ? Vector2(x.z(), x.x()) : Vector2(x.x(), x.y()));
}

bool inBox(const Vector2& p, const Vector2& a, const Vector2& b) {
  return (p.array() >= a.array().min(b.array())).all() && (p.array() <= a.array().max(b.array())).all();
}

/// Closed segments pq and rs of the plane meet.
bool segmentsIntersect2d(const Vector2& p, const Vector2& q, const Vector2& r, const Vector2& s) {
  const int o1 = orientation2d(p, q, r), o2 = orientation2d(p, q, s);
  const int o3 = orientation2d(r, s, p), o4 = orientation2d(r, s, q);
  // All four points on one line (or a segment is a point on the other's line): the segments
  // are intervals of that line, which meet iff their boxes do.
  if (o1 == 0 && o2 == 0 && o3 == 0 && o4 == 0) {
    return (p.array().min(q.array()) <= r.array().max(s.array())).all() &&
           (r.array().min(s.array()) <= p.array().max(q.array())).all();
  }
  return o1 * o2 <= 0 && o3 * o4 <= 0;
}

/// Point p lies in the closed (possibly zero-area) triangle abc of the plane.
bool pointInTriangle2d(const Vector2& p, const Vector2& a, const Vector2& b, const Vector2& c) {
  const int orientation = orientation2d(a, b, c);
  if (orientation != 0) {
    return orientation2d(a, b, p) * orientation >= 0 && orientation2d(b, c, p) * orientation >= 0 &&
           orientation2d(c, a, p) * orientation >= 0;
  }
  auto onSegment = [&](const Vector2& x, const Vector2& y) { return orientation2d(x, y, p) == 0 && inBox(p, x, y); };
  return onSegment(a, b) || onSegment(b, c) || onSegment(c, a);
}

/// The closed segment de meets the closed triangle abc of the plane.
bool segmentTriangleIntersect2d(const Vector2& d, const Vector2& e, const Vector2& a, const Vector2& b,
                                const Vector2& c) {
  return pointInTriangle2d(d, a, b, c) || segmentsIntersect2d(d, e, a, b) || segmentsIntersect2d(d, e, b, c) ||
         segmentsIntersect2d(d, e, c, a);
}

/// For a coplanar (or collinear) configuration, a test holds in 3D iff it holds in all
/// three coordinate projections: each projection maps meeting sets to meeting sets, and at
/// least one is one-to-one on the common plane (or line).
template <typename Test>
bool inEveryProjection(Test test) {
  return test(0) && test(1) && test(2);
}

/// Closed segments pq and rs of space meet.
bool segmentsIntersect3d(const Vector3& p, const Vector3& q, const Vector3& r, const Vector3& s) {
  if (orientation3d(p, q, r, s) != 0) return false;
  return inEveryProjection([&](int axis) {
    return segmentsIntersect2d(project(p, axis), project(q, axis), project(r, axis), project(s, axis));
  });
}

/// abc has zero area exactly: every projection of it has zero area.
bool degenerate(const Vector3& a, const Vector3& b, const Vector3& c) {
  return inEveryProjection(
      [&](int axis) { return orientation2d(project(a, axis), project(b, axis), project(c, axis)) == 0; });
}

/// The closed segment de meets the closed triangle abc.
bool segmentTriangleIntersect(const Vector3& d, const Vector3& e, const Vector3& a, const Vector3& b,
                              const Vector3& c) {
  if (degenerate(a, b, c))
    return segmentsIntersect3d(d, e, a, b) || segmentsIntersect3d(d, e, b, c) || segmentsIntersect3d(d, e, c, a);
  const int sideD = orientation3d(a, b, c, d), sideE = orientation3d(a, b, c, e);
  if (sideD * sideE > 0) return false;  // both strictly on one side of the plane
  if (sideD == 0 && sideE == 0) {
    return inEveryProjection([&](int axis) {
      return segmentTriangleIntersect2d(project(d, axis), project(e, axis), project(a, axis), project(b, axis),
                                        project(c, axis));
    });
  }
  // de meets the plane in one point; it lies in the triangle iff the line de passes on the
  // same side of (or through) all three edges.
  const int ab = orientation3d(d, e, a, b), bc = orientation3d(d, e, b, c), ca = orientation3d(d, e, c, a);
  return (ab >= 0 && bc >= 0 && ca >= 0) || (ab <= 0 && bc <= 0 && ca <= 0);
}

bool triangleMeetsEdgesOf(const std::array<const Vector3*, 3>& triangle, const std::array<const Vector3*, 3>& other) {
  for (std::size_t i = 0; i < 3; ++i) {
    if (segmentTriangleIntersect(*other[i], *other[(i + 1) % 3], *triangle[0], *triangle[1], *triangle[2])) return true;
  }
  return false;
}

bool trianglesIntersectAt(const CollisionSurface& first, const Eigen::Matrix3Xd& firstPositions, int i,
                          const CollisionSurface& second, const Eigen::Matrix3Xd& secondPositions, int j) {
  auto corner = [](const CollisionSurface& s, const Eigen::Matrix3Xd& x, int t, int c) {
    return Vector3(x.col(s.triangles(c, t)));
  };
  return trianglesIntersect(corner(first, firstPositions, i, 0), corner(first, firstPositions, i, 1),
                            corner(first, firstPositions, i, 2), corner(second, secondPositions, j, 0),
                            corner(second, secondPositions, j, 1), corner(second, secondPositions, j, 2));
}

}  // namespace

bool trianglesIntersect(const Vector3& a0, const Vector3& a1, const Vector3& a2, const Vector3& b0, const Vector3& b1,
                        const Vector3& b2) {
  // Their intersection is convex; its extreme points lie on the boundary of one triangle.
  const std::array<const Vector3*, 3> a{&a0, &a1, &a2};
  const std::array<const Vector3*, 3> b{&b0, &b1, &b2};
  return triangleMeetsEdgesOf(a, b) || triangleMeetsEdgesOf(b, a);
}

std::vector<std::pair<int, int>> intersectingTrianglePairs(const CollisionSurface& first,
                                                           const Eigen::Matrix3Xd& firstPositions,
                                                           const CollisionSurface& second,
                                                           const Eigen::Matrix3Xd& secondPositions,
                                                           BroadPhaseMethod method) {
  checkPositions(first, firstPositions, "intersectingTrianglePairs (first surface)");
  checkPositions(second, secondPositions, "intersectingTrianglePairs (second surface)");
  std::vector<std::pair<int, int>> pairs;
  for (const auto& [i, j] : overlappingBoxes(triangleBoxes(first, firstPositions, 0.0),
                                             triangleBoxes(second, secondPositions, 0.0), method)) {
    if (trianglesIntersectAt(first, firstPositions, i, second, secondPositions, j)) pairs.emplace_back(i, j);
  }
  return pairs;
}

std::vector<std::pair<int, int>> selfIntersectingTrianglePairs(const CollisionSurface& surface,
                                                               const Eigen::Matrix3Xd& positions,
                                                               BroadPhaseMethod method) {
  checkPositions(surface, positions, "selfIntersectingTrianglePairs");
  std::vector<std::pair<int, int>> pairs;
  for (const auto& [i, j] : overlappingBoxes(triangleBoxes(surface, positions, 0.0), method)) {
    const Eigen::Vector3i a = surface.triangles.col(i), b = surface.triangles.col(j);
    bool shareVertex = false;
    for (int k = 0; k < 3; ++k) shareVertex = shareVertex || (b.array() == a[k]).any();
    if (!shareVertex && trianglesIntersectAt(surface, positions, i, surface, positions, j)) pairs.emplace_back(i, j);
  }
  return pairs;
}

}  // namespace asyncfem
