// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Geometry>
#include <array>
#include <asyncfem/collision/distance.hpp>
#include <limits>

namespace asyncfem {

namespace {

using Matrix3 = Eigen::Matrix3d;
using Vector3 = Eigen::Vector3d;

// Below this sin^2 of the angle between two edges (or two sides of a triangle) the line-line
// (or point-plane) form divides by a cross product that is mostly round-off; the endpoint
// forms are used instead (docs/collision.md, "Distance sub-cases").
constexpr double kParallelSinSquared = 1e-14;

Matrix3 crossMatrix(const Vector3& v) {
  Matrix3 m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

/// A closed form f(d_1, ..., d_k) of k difference vectors of the four points, with
/// derivatives with respect to the d_i (3k entries).
template <int K>
struct LocalForm {
  double value = 0.0;
  Eigen::Matrix<double, 3 * K, 1> gradient;
  Eigen::Matrix<double, 3 * K, 3 * K> hessian;
};

/// Eq. D1: f(r) = r.r.
LocalForm<1> pointPointForm(const Vector3& r) {
  LocalForm<1> form;
  form.value = r.squaredNorm();
  form.gradient = 2.0 * r;
  form.hessian = 2.0 * Matrix3::Identity();
  return form;
}

/// Eq. D2: f(r, e) = r.r - s^2 / q with s = r.e, q = e.e (squared distance of the point r
/// from the line through the origin along e). NaN for e = 0.
LocalForm<2> pointLineForm(const Vector3& r, const Vector3& e) {
  LocalForm<2> form;
  const double s = r.dot(e);
  const double q = e.squaredNorm();
  const Matrix3 identity = Matrix3::Identity();
  form.value = r.squaredNorm() - s * s / q;
  form.gradient << 2.0 * r - 2.0 * s / q * e, -2.0 * s / q * r + 2.0 * s * s / (q * q) * e;
  const Matrix3 hrr = 2.0 * identity - 2.0 / q * e * e.transpose();
  // d/de of df/dr = -2 s e / q: -2 (e r^T + s I) / q + 4 s e e^T / q^2.
  const Matrix3 hre = -2.0 / q * (e * r.transpose() + s * identity) + 4.0 * s / (q * q) * e * e.transpose();
  const Matrix3 hee = -2.0 / q * r * r.transpose() + 4.0 * s / (q * q) * (r * e.transpose() + e * r.transpose()) +
                      2.0 * s * s / (q * q) * identity - 8.0 * s * s / (q * q * q) * e * e.transpose();
  form.hessian << hrr, hre, hre.transpose(), hee;
  return form;
}

/// Eq. D3: f(r, u, w) = g^2 / m with n = u x w, g = r.n, m = n.n (squared distance of the
/// point r from the plane through the origin spanned by u and w). NaN for u x w = 0.
LocalForm<3> pointPlaneForm(const Vector3& r, const Vector3& u, const Vector3& w) {
  LocalForm<3> form;
  const Vector3 n = u.cross(w);
  const double g = r.dot(n);
  const double m = n.squaredNorm();
  form.value = g * g / m;
  // g = r.(u x w) is trilinear: dg/dr = n, dg/du = w x r, dg/dw = r x u.
  Eigen::Matrix<double, 9, 1> dg;
  dg << n, w.cross(r), r.cross(u);
  Eigen::Matrix<double, 9, 9> d2g = Eigen::Matrix<double, 9, 9>::Zero();
  d2g.block<3, 3>(0, 3) = -crossMatrix(w);
  d2g.block<3, 3>(0, 6) = crossMatrix(u);
  d2g.block<3, 3>(3, 6) = -crossMatrix(r);
  d2g.block<3, 3>(3, 0) = d2g.block<3, 3>(0, 3).transpose();
  d2g.block<3, 3>(6, 0) = d2g.block<3, 3>(0, 6).transpose();
  d2g.block<3, 3>(6, 3) = d2g.block<3, 3>(3, 6).transpose();
  // m = |u x w|^2: dm/du = 2 w x n, dm/dw = 2 n x u; d2m = 2 Jn^T Jn + 2 sum_k n_k d2n_k with
  // Jn = [-[w]x, [u]x] the derivative of n, and sum_k n_k d2n_k/du dw = -[n]x.
  Eigen::Matrix<double, 9, 1> dm = Eigen::Matrix<double, 9, 1>::Zero();
  dm.segment<3>(3) = 2.0 * w.cross(n);
  dm.segment<3>(6) = 2.0 * n.cross(u);
  Eigen::Matrix<double, 3, 6> jn;
  jn << -crossMatrix(w), crossMatrix(u);
  Eigen::Matrix<double, 9, 9> d2m = Eigen::Matrix<double, 9, 9>::Zero();
  d2m.block<6, 6>(3, 3) = 2.0 * jn.transpose() * jn;
  d2m.block<3, 3>(3, 6) -= 2.0 * crossMatrix(n);
  d2m.block<3, 3>(6, 3) += 2.0 * crossMatrix(n);
  form.gradient = 2.0 * g / m * dg - g * g / (m * m) * dm;
  form.hessian = 2.0 / m * dg * dg.transpose() + 2.0 * g / m * d2g -
                 2.0 * g / (m * m) * (dg * dm.transpose() + dm * dg.transpose()) +
                 2.0 * g * g / (m * m * m) * dm * dm.transpose() - g * g / (m * m) * d2m;
  return form;
}

/// The four points as one array so that forms can name them by index.
using Points = std::array<Vector3, 4>;

/// Which closed form applies and its difference vectors d_i = x[plus_i] - x[minus_i]:
/// PointPoint uses d_0 = r; PointEdge d_0 = r, d_1 = e; PointPlane and LineLine d_0 = r,
/// d_1 = u, d_2 = w.
struct FormIndices {
  DistanceKind kind;
  std::array<int, 3> plus;
  std::array<int, 3> minus;
};

Vector3 difference(const Points& x, const FormIndices& form, std::size_t i) {
  return x[static_cast<std::size_t>(form.plus[i])] - x[static_cast<std::size_t>(form.minus[i])];
}

/// Scatters a local form's derivatives to the 12 coordinates of the four points through
/// d_i = x[plus_i] - x[minus_i].
template <int K>
SquaredDistance scatter(const LocalForm<K>& local, const FormIndices& form) {
  SquaredDistance result;
  result.value = local.value;
  for (int i = 0; i < K; ++i) {
    const auto si = static_cast<std::size_t>(i);
    result.gradient.segment<3>(3 * form.plus[si]) += local.gradient.template segment<3>(3 * i);
    result.gradient.segment<3>(3 * form.minus[si]) -= local.gradient.template segment<3>(3 * i);
    for (int j = 0; j < K; ++j) {
      const auto sj = static_cast<std::size_t>(j);
      const Matrix3 block = local.hessian.template block<3, 3>(3 * i, 3 * j);
      result.hessian.block<3, 3>(3 * form.plus[si], 3 * form.plus[sj]) += block;
      result.hessian.block<3, 3>(3 * form.plus[si], 3 * form.minus[sj]) -= block;
      result.hessian.block<3, 3>(3 * form.minus[si], 3 * form.plus[sj]) -= block;
      result.hessian.block<3, 3>(3 * form.minus[si], 3 * form.minus[sj]) += block;
    }
  }
  return result;
}

SquaredDistance evaluate(const Points& x, const FormIndices& form) {
  switch (form.kind) {
    case DistanceKind::PointPoint:
      return scatter(pointPointForm(difference(x, form, 0)), form);
    case DistanceKind::PointEdge:
      return scatter(pointLineForm(difference(x, form, 0), difference(x, form, 1)), form);
    case DistanceKind::PointPlane:
    case DistanceKind::LineLine:
      break;
  }
  return scatter(pointPlaneForm(difference(x, form, 0), difference(x, form, 1), difference(x, form, 2)), form);
}

double pointLineValue(const Vector3& r, const Vector3& e) {
  const double s = r.dot(e);
  return r.squaredNorm() - s * s / e.squaredNorm();
}

/// The value of evaluate() without derivatives.
double evaluateValue(const Points& x, const FormIndices& form) {
  const Vector3 r = difference(x, form, 0);
  switch (form.kind) {
    case DistanceKind::PointPoint:
      return r.squaredNorm();
    case DistanceKind::PointEdge:
      return pointLineValue(r, difference(x, form, 1));
    case DistanceKind::PointPlane:
    case DistanceKind::LineLine:
      break;
  }
  const Vector3 n = difference(x, form, 1).cross(difference(x, form, 2));
  const double g = r.dot(n);
  return g * g / n.squaredNorm();
}

/// Points (p, a, b, c) = indices 0..3.
FormIndices pointTriangleForm(PointTriangleRegion region) {
  switch (region) {
    case PointTriangleRegion::VertexA:
      return {DistanceKind::PointPoint, {0, 0, 0}, {1, 0, 0}};
    case PointTriangleRegion::VertexB:
      return {DistanceKind::PointPoint, {0, 0, 0}, {2, 0, 0}};
    case PointTriangleRegion::VertexC:
      return {DistanceKind::PointPoint, {0, 0, 0}, {3, 0, 0}};
    case PointTriangleRegion::EdgeAB:
      return {DistanceKind::PointEdge, {0, 2, 0}, {1, 1, 0}};
    case PointTriangleRegion::EdgeBC:
      return {DistanceKind::PointEdge, {0, 3, 0}, {2, 2, 0}};
    case PointTriangleRegion::EdgeCA:
      return {DistanceKind::PointEdge, {0, 1, 0}, {3, 3, 0}};
    case PointTriangleRegion::Face:
      break;
  }
  return {DistanceKind::PointPlane, {0, 2, 3}, {1, 1, 1}};
}

/// Points (a0, a1, b0, b1) = indices 0..3.
FormIndices edgeEdgeForm(EdgeEdgeRegion region) {
  switch (region) {
    case EdgeEdgeRegion::A0B0:
      return {DistanceKind::PointPoint, {0, 0, 0}, {2, 0, 0}};
    case EdgeEdgeRegion::A0B1:
      return {DistanceKind::PointPoint, {0, 0, 0}, {3, 0, 0}};
    case EdgeEdgeRegion::A1B0:
      return {DistanceKind::PointPoint, {1, 0, 0}, {2, 0, 0}};
    case EdgeEdgeRegion::A1B1:
      return {DistanceKind::PointPoint, {1, 0, 0}, {3, 0, 0}};
    case EdgeEdgeRegion::A0EdgeB:
      return {DistanceKind::PointEdge, {0, 3, 0}, {2, 2, 0}};
    case EdgeEdgeRegion::A1EdgeB:
      return {DistanceKind::PointEdge, {1, 3, 0}, {2, 2, 0}};
    case EdgeEdgeRegion::B0EdgeA:
      return {DistanceKind::PointEdge, {2, 1, 0}, {0, 0, 0}};
    case EdgeEdgeRegion::B1EdgeA:
      return {DistanceKind::PointEdge, {3, 1, 0}, {0, 0, 0}};
    case EdgeEdgeRegion::Interior:
      break;
  }
  // r = b0 - a0, u = a1 - a0, w = b1 - b0.
  return {DistanceKind::LineLine, {2, 1, 3}, {0, 0, 2}};
}

/// Closest-point parameter of p on the segment (a, b), clamped to [0, 1] (0 for a = b).
double segmentParameter(const Vector3& p, const Vector3& a, const Vector3& b) {
  const Vector3 e = b - a;
  const double q = e.squaredNorm();
  if (q == 0.0) return 0.0;
  const double t = (p - a).dot(e) / q;
  return t <= 0.0 ? 0.0 : (t >= 1.0 ? 1.0 : t);
}

double pointSegmentDistanceSquared(const Vector3& p, const Vector3& a, const Vector3& b) {
  const double t = segmentParameter(p, a, b);
  if (t == 0.0) return (p - a).squaredNorm();
  if (t == 1.0) return (p - b).squaredNorm();
  return pointLineValue(p - a, b - a);
}

/// 0: the segment's start, 1: its end, 2: its inside.
int segmentPart(double t) { return t == 0.0 ? 0 : (t == 1.0 ? 1 : 2); }

}  // namespace

DistanceKind distanceKind(PointTriangleRegion region) {
  switch (region) {
    case PointTriangleRegion::VertexA:
    case PointTriangleRegion::VertexB:
    case PointTriangleRegion::VertexC:
      return DistanceKind::PointPoint;
    case PointTriangleRegion::EdgeAB:
    case PointTriangleRegion::EdgeBC:
    case PointTriangleRegion::EdgeCA:
      return DistanceKind::PointEdge;
    case PointTriangleRegion::Face:
      break;
  }
  return DistanceKind::PointPlane;
}

DistanceKind distanceKind(EdgeEdgeRegion region) {
  switch (region) {
    case EdgeEdgeRegion::A0B0:
    case EdgeEdgeRegion::A0B1:
    case EdgeEdgeRegion::A1B0:
    case EdgeEdgeRegion::A1B1:
      return DistanceKind::PointPoint;
    case EdgeEdgeRegion::A0EdgeB:
    case EdgeEdgeRegion::A1EdgeB:
    case EdgeEdgeRegion::B0EdgeA:
    case EdgeEdgeRegion::B1EdgeA:
      return DistanceKind::PointEdge;
    case EdgeEdgeRegion::Interior:
      break;
  }
  return DistanceKind::LineLine;
}

PointTriangleRegion pointTriangleRegion(const Vector3& p, const Vector3& a, const Vector3& b, const Vector3& c) {
  const Vector3 ab = b - a;
  const Vector3 ac = c - a;
  const Vector3 n = ab.cross(ac);
  // |p - x|^2 = (distance to the plane)^2 + |p' - x|^2 for the projection p' of p, so the
  // closest point is p' when p' is in the triangle, else the closest point of its boundary.
  if (n.squaredNorm() > kParallelSinSquared * ab.squaredNorm() * ac.squaredNorm()) {
    const bool insideAB = ab.cross(p - a).dot(n) >= 0.0;
    const bool insideBC = (c - b).cross(p - b).dot(n) >= 0.0;
    const bool insideCA = (a - c).cross(p - c).dot(n) >= 0.0;
    if (insideAB && insideBC && insideCA) return PointTriangleRegion::Face;
  }
  const std::array<const Vector3*, 3> corners{&a, &b, &c};
  constexpr std::array<PointTriangleRegion, 3> kEdges{PointTriangleRegion::EdgeAB, PointTriangleRegion::EdgeBC,
                                                      PointTriangleRegion::EdgeCA};
  constexpr std::array<PointTriangleRegion, 3> kVertices{PointTriangleRegion::VertexA, PointTriangleRegion::VertexB,
                                                         PointTriangleRegion::VertexC};
  double best = std::numeric_limits<double>::infinity();
  PointTriangleRegion region = PointTriangleRegion::VertexA;
  for (std::size_t i = 0; i < 3; ++i) {
    const std::size_t j = (i + 1) % 3;
    const double t = segmentParameter(p, *corners[i], *corners[j]);
    const double d = pointSegmentDistanceSquared(p, *corners[i], *corners[j]);
    if (d < best) {
      best = d;
      const int part = segmentPart(t);
      region = part == 0 ? kVertices[i] : (part == 1 ? kVertices[j] : kEdges[i]);
    }
  }
  return region;
}

SquaredDistance pointTriangleDistance(const Vector3& p, const Vector3& a, const Vector3& b, const Vector3& c,
                                      PointTriangleRegion region) {
  return evaluate({p, a, b, c}, pointTriangleForm(region));
}

SquaredDistance pointTriangleDistance(const Vector3& p, const Vector3& a, const Vector3& b, const Vector3& c) {
  return pointTriangleDistance(p, a, b, c, pointTriangleRegion(p, a, b, c));
}

double pointTriangleDistanceSquared(const Vector3& p, const Vector3& a, const Vector3& b, const Vector3& c) {
  return evaluateValue({p, a, b, c}, pointTriangleForm(pointTriangleRegion(p, a, b, c)));
}

EdgeEdgeRegion edgeEdgeRegion(const Vector3& a0, const Vector3& a1, const Vector3& b0, const Vector3& b1) {
  const Vector3 u = a1 - a0;
  const Vector3 w = b1 - b0;
  const Vector3 r = a0 - b0;
  const double uu = u.squaredNorm();
  const double uw = u.dot(w);
  const double ww = w.squaredNorm();
  const double denominator = u.cross(w).squaredNorm();  // uu ww - uw^2, without cancellation
  if (denominator > kParallelSinSquared * uu * ww) {
    // Stationary point of |a0 + s u - b0 - t w|^2: s = (uw (w.r) - ww (u.r)) / den,
    // t = (uu (w.r) - uw (u.r)) / den. Inside the unit square it is the minimum.
    const double s = (uw * w.dot(r) - ww * u.dot(r)) / denominator;
    const double t = (uu * w.dot(r) - uw * u.dot(r)) / denominator;
    if (s >= 0.0 && s <= 1.0 && t >= 0.0 && t <= 1.0) return EdgeEdgeRegion::Interior;
  }
  // Otherwise the minimum of the convex quadratic over the square lies on its boundary: an
  // endpoint of one edge against the other edge.
  struct Candidate {
    const Vector3* point;
    const Vector3* start;
    const Vector3* end;
    EdgeEdgeRegion atStart, atEnd, inside;
  };
  const std::array<Candidate, 4> candidates{{
      {&a0, &b0, &b1, EdgeEdgeRegion::A0B0, EdgeEdgeRegion::A0B1, EdgeEdgeRegion::A0EdgeB},
      {&a1, &b0, &b1, EdgeEdgeRegion::A1B0, EdgeEdgeRegion::A1B1, EdgeEdgeRegion::A1EdgeB},
      {&b0, &a0, &a1, EdgeEdgeRegion::A0B0, EdgeEdgeRegion::A1B0, EdgeEdgeRegion::B0EdgeA},
      {&b1, &a0, &a1, EdgeEdgeRegion::A0B1, EdgeEdgeRegion::A1B1, EdgeEdgeRegion::B1EdgeA},
  }};
  double best = std::numeric_limits<double>::infinity();
  EdgeEdgeRegion region = EdgeEdgeRegion::A0B0;
  for (const Candidate& candidate : candidates) {
    const double t = segmentParameter(*candidate.point, *candidate.start, *candidate.end);
    const double d = pointSegmentDistanceSquared(*candidate.point, *candidate.start, *candidate.end);
    if (d < best) {
      best = d;
      const int part = segmentPart(t);
      region = part == 0 ? candidate.atStart : (part == 1 ? candidate.atEnd : candidate.inside);
    }
  }
  return region;
}

SquaredDistance edgeEdgeDistance(const Vector3& a0, const Vector3& a1, const Vector3& b0, const Vector3& b1,
                                 EdgeEdgeRegion region) {
  return evaluate({a0, a1, b0, b1}, edgeEdgeForm(region));
}

SquaredDistance edgeEdgeDistance(const Vector3& a0, const Vector3& a1, const Vector3& b0, const Vector3& b1) {
  return edgeEdgeDistance(a0, a1, b0, b1, edgeEdgeRegion(a0, a1, b0, b1));
}

double edgeEdgeDistanceSquared(const Vector3& a0, const Vector3& a1, const Vector3& b0, const Vector3& b1) {
  return evaluateValue({a0, a1, b0, b1}, edgeEdgeForm(edgeEdgeRegion(a0, a1, b0, b1)));
}

}  // namespace asyncfem
