// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Geometry>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/implicit.hpp>
#include <cmath>
#include <utility>

namespace asyncfem {

namespace {

void requirePositive(double value, const char* what) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw ValidationError(std::string("implicit primitive: ") + what + " must be a finite number > 0, got " +
                          std::to_string(value));
  }
}

/// Parameter t in [0, 1] of the point of segment [a, b] closest to x.
double segmentParameter(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double lengthSquared = ab.squaredNorm();
  if (lengthSquared == 0.0) return 0.0;
  return std::clamp((x - a).dot(ab) / lengthSquared, 0.0, 1.0);
}

double smoothMin(double a, double b, double blend) {
  if (blend <= 0.0) return std::min(a, b);
  const double overlap = std::max(blend - std::abs(a - b), 0.0);
  return std::min(a, b) - overlap * overlap / (4.0 * blend);
}

}  // namespace

ImplicitFunction implicitSphere(const Eigen::Vector3d& center, double radius) {
  requirePositive(radius, "sphere radius");
  return [center, radius](const Eigen::Vector3d& x) { return (x - center).norm() - radius; };
}

ImplicitFunction implicitCapsule(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius) {
  return implicitTaperedCapsule(a, b, radius, radius);
}

ImplicitFunction implicitTaperedCapsule(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radiusA,
                                        double radiusB) {
  requirePositive(radiusA, "capsule radius");
  requirePositive(radiusB, "capsule radius");
  return [a, b, radiusA, radiusB](const Eigen::Vector3d& x) {
    const double t = segmentParameter(x, a, b);
    return (x - (a + t * (b - a))).norm() - ((1.0 - t) * radiusA + t * radiusB);
  };
}

ImplicitFunction implicitEllipsoid(const Eigen::Vector3d& center, const Eigen::Vector3d& radii) {
  for (int i = 0; i < 3; ++i) requirePositive(radii[i], "ellipsoid radius");
  const double smallest = radii.minCoeff();
  return [center, radii, smallest](const Eigen::Vector3d& x) {
    return ((x - center).cwiseQuotient(radii).norm() - 1.0) * smallest;
  };
}

ImplicitFunction implicitOrientedEllipsoid(const Eigen::Vector3d& center, const Eigen::Vector3d& axis,
                                           const Eigen::Vector3d& up, const Eigen::Vector3d& radii) {
  const Eigen::Vector3d e0 = axis.normalized();
  Eigen::Vector3d e1 = up - up.dot(e0) * e0;
  if (!(e1.norm() > 1e-12)) throw ValidationError("implicit primitive: ellipsoid axis and up are parallel");
  e1.normalize();
  const Eigen::Vector3d e2 = e0.cross(e1);
  Eigen::Matrix3d frame;
  frame.row(0) = e0.transpose();
  frame.row(1) = e1.transpose();
  frame.row(2) = e2.transpose();
  const ImplicitFunction local = implicitEllipsoid(Eigen::Vector3d::Zero(), radii);
  return [center, frame, local](const Eigen::Vector3d& x) { return local(frame * (x - center)); };
}

ImplicitFunction implicitBox(const Eigen::Vector3d& center, const Eigen::Vector3d& halfSize, double rounding) {
  for (int i = 0; i < 3; ++i) requirePositive(halfSize[i], "box half size");
  if (rounding < 0.0 || rounding >= halfSize.minCoeff()) {
    throw ValidationError("implicit primitive: box rounding must be in [0, smallest half size)");
  }
  const Eigen::Vector3d inner = halfSize.array() - rounding;
  return [center, inner, rounding](const Eigen::Vector3d& x) {
    const Eigen::Vector3d q = (x - center).cwiseAbs() - inner;
    return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0) - rounding;
  };
}

ImplicitFunction implicitTorus(const Eigen::Vector3d& center, const Eigen::Vector3d& axis, double majorRadius,
                               double minorRadius) {
  requirePositive(majorRadius, "torus major radius");
  requirePositive(minorRadius, "torus minor radius");
  const Eigen::Vector3d n = axis.normalized();
  return [center, n, majorRadius, minorRadius](const Eigen::Vector3d& x) {
    const Eigen::Vector3d d = x - center;
    const double height = d.dot(n);
    const double radial = (d - height * n).norm();
    return std::hypot(radial - majorRadius, height) - minorRadius;
  };
}

ImplicitFunction implicitUnion(std::vector<ImplicitFunction> parts) {
  return implicitSmoothUnion(std::move(parts), 0.0);
}

ImplicitFunction implicitSmoothUnion(std::vector<ImplicitFunction> parts, double blend) {
  if (parts.empty()) throw ValidationError("implicit union: no parts");
  if (blend < 0.0 || !std::isfinite(blend)) throw ValidationError("implicit union: blend width must be >= 0");
  return [parts = std::move(parts), blend](const Eigen::Vector3d& x) {
    double value = parts.front()(x);
    for (std::size_t i = 1; i < parts.size(); ++i) value = smoothMin(value, parts[i](x), blend);
    return value;
  };
}

ImplicitFunction implicitIntersection(ImplicitFunction a, ImplicitFunction b) {
  return [a = std::move(a), b = std::move(b)](const Eigen::Vector3d& x) { return std::max(a(x), b(x)); };
}

ImplicitFunction implicitDifference(ImplicitFunction a, ImplicitFunction b) {
  return [a = std::move(a), b = std::move(b)](const Eigen::Vector3d& x) { return std::max(a(x), -b(x)); };
}

ImplicitFunction implicitUnionOfParts(const std::vector<ImplicitPart>& parts, double blend) {
  std::vector<ImplicitFunction> functions;
  functions.reserve(parts.size());
  for (const ImplicitPart& part : parts) functions.push_back(part.function);
  return implicitSmoothUnion(std::move(functions), blend);
}

}  // namespace asyncfem
