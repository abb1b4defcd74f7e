// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>

namespace asyncfem {

/// The closed form a squared distance takes (docs/collision.md, "Distance sub-cases"):
/// - PointPoint: |p - q|^2 (Eq. D1);
/// - PointEdge: squared distance of a point to the line through an edge, |r|^2 - (r.e)^2 / |e|^2
///   with r = p - a, e = b - a (Eq. D2);
/// - PointPlane: squared distance of a point to the plane of a triangle, (n.r)^2 / |n|^2 with
///   n = (b - a) x (c - a), r = p - a (Eq. D3);
/// - LineLine: squared distance between the lines through two edges, (n.r)^2 / |n|^2 with
///   n = (a1 - a0) x (b1 - b0), r = b0 - a0 (Eq. D3 again).
enum class DistanceKind { PointPoint, PointEdge, PointPlane, LineLine };

/// Where the closest point of triangle (a, b, c) to a point lies: a corner, the inside of an
/// edge, or the inside of the face.
enum class PointTriangleRegion { VertexA, VertexB, VertexC, EdgeAB, EdgeBC, EdgeCA, Face };

/// Where the closest points of edges (a0, a1) and (b0, b1) lie. A0B0..A1B1: two endpoints;
/// A0EdgeB: endpoint a0 and the inside of edge b (likewise the others); Interior: the
/// insides of both edges (the lines' closest points).
enum class EdgeEdgeRegion { A0B0, A0B1, A1B0, A1B1, A0EdgeB, A1EdgeB, B0EdgeA, B1EdgeA, Interior };

/// The closed form that applies in each region.
DistanceKind distanceKind(PointTriangleRegion region);
DistanceKind distanceKind(EdgeEdgeRegion region);

/// A squared distance (length^2) and its derivatives with respect to the four points' 12
/// coordinates stacked point after point (x, y, z of the first point, then the second, ...):
/// gradient 12 (length), Hessian 12 x 12 (dimensionless), symmetric.
struct SquaredDistance {
  double value = 0.0;
  Eigen::Matrix<double, 12, 1> gradient = Eigen::Matrix<double, 12, 1>::Zero();
  Eigen::Matrix<double, 12, 12> hessian = Eigen::Matrix<double, 12, 12>::Zero();
};

/// Region of the closest point of the closed triangle (a, b, c) to p. The face counts when
/// p projects inside or onto the boundary of the triangle; otherwise the closest point of
/// the three edges decides. A triangle whose sides at a make sin^2(angle) <= 1e-14 (zero or
/// nearly zero area) is its edges: its closest point moves by at most its width, below 1e-7
/// of its sides. Ties between edges go to the first of AB, BC, CA.
PointTriangleRegion pointTriangleRegion(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                        const Eigen::Vector3d& c);

/// Squared distance between point p and the closed triangle (a, b, c) (length^2).
double pointTriangleDistanceSquared(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c);

/// Squared distance between p and triangle (a, b, c) with its gradient and Hessian with
/// respect to (p, a, b, c), from the closed form of `region` (Eqs. D1-D3). Pass the region
/// pointTriangleRegion returns; another one gives that form's value (the distance to the
/// line, plane or vertex it names), which is what a contact model that keeps a region
/// fixed over a Newton step wants. A form that does not exist for the input (the line of a
/// zero-length edge, the plane of a zero-area triangle, the common normal of parallel
/// edges) gives NaN.
SquaredDistance pointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                      const Eigen::Vector3d& c, PointTriangleRegion region);
/// The same, in the region pointTriangleRegion finds.
SquaredDistance pointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                      const Eigen::Vector3d& c);

/// Region of the closest points of the closed segments (a0, a1) and (b0, b1). Interior when
/// the lines' closest points lie inside both segments and the edges are not parallel
/// (sin^2 of their angle above 1e-14; below it the lines' distance is ill-conditioned and
/// an endpoint form is used, which differs from the exact squared distance by order
/// 1e-14 * (edge length)^2); otherwise the endpoint whose point-segment distance is
/// smallest (ties to the first in A0, A1, B0, B1 order).
EdgeEdgeRegion edgeEdgeRegion(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& b0,
                              const Eigen::Vector3d& b1);

/// Squared distance between the closed segments (a0, a1) and (b0, b1) (length^2).
double edgeEdgeDistanceSquared(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& b0,
                               const Eigen::Vector3d& b1);

/// Squared distance between edges (a0, a1) and (b0, b1) with gradient and Hessian with
/// respect to (a0, a1, b0, b1), from the closed form of `region` (see pointTriangleDistance).
SquaredDistance edgeEdgeDistance(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& b0,
                                 const Eigen::Vector3d& b1, EdgeEdgeRegion region);
/// The same, in the region edgeEdgeRegion finds.
SquaredDistance edgeEdgeDistance(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& b0,
                                 const Eigen::Vector3d& b1);

}  // namespace asyncfem
