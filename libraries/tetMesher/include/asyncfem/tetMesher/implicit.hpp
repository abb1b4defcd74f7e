// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

namespace asyncfem {

/// An implicit solid: f(x) < 0 inside, f(x) > 0 outside, f(x) = 0 on the surface. Values
/// are lengths (a signed distance or a bound of the same sign and magnitude near the
/// surface). The mesher may call it from several threads at once, so it must not mutate
/// shared state.
using ImplicitFunction = std::function<double(const Eigen::Vector3d&)>;

/// Sphere of radius r around center: |x - c| - r (exact signed distance).
ImplicitFunction implicitSphere(const Eigen::Vector3d& center, double radius);

/// Capsule: points within radius of the segment [a, b] (exact signed distance).
ImplicitFunction implicitCapsule(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius);

/// Tapered capsule: the radius varies linearly from radiusA at a to radiusB at b along the
/// segment; f = dist(x, closest point at parameter t) - r(t). A Lipschitz bound rather than
/// the exact distance where the radii differ; exact for equal radii.
ImplicitFunction implicitTaperedCapsule(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radiusA,
                                        double radiusB);

/// Axis-aligned ellipsoid with semi-axes radii around center; f = (|(x-c)/r| - 1) min(r),
/// which has the ellipsoid as zero set and the right sign (not an exact distance).
ImplicitFunction implicitEllipsoid(const Eigen::Vector3d& center, const Eigen::Vector3d& radii);

/// Ellipsoid whose semi-axis radii.x lies along the unit direction `axis` and whose other two
/// semi-axes are radii.y (in the plane spanned by axis and `up`) and radii.z (normal to it).
ImplicitFunction implicitOrientedEllipsoid(const Eigen::Vector3d& center, const Eigen::Vector3d& axis,
                                           const Eigen::Vector3d& up, const Eigen::Vector3d& radii);

/// Axis-aligned box [center - halfSize, center + halfSize] with edges rounded by
/// rounding (0 <= rounding < min halfSize); exact signed distance.
ImplicitFunction implicitBox(const Eigen::Vector3d& center, const Eigen::Vector3d& halfSize, double rounding = 0.0);

/// Torus around the axis through center along the unit vector axis: major radius R, tube
/// radius r; exact signed distance.
ImplicitFunction implicitTorus(const Eigen::Vector3d& center, const Eigen::Vector3d& axis, double majorRadius,
                               double minorRadius);

/// Sharp union min(f_i) of one or more functions.
ImplicitFunction implicitUnion(std::vector<ImplicitFunction> parts);

/// Smooth union of one or more functions: the polynomial smooth minimum with blend width
/// k (lengths): smin(a, b) = min(a, b) - max(k - |a - b|, 0)^2 / (4k), applied pairwise
/// left to right. k = 0 is the sharp union.
ImplicitFunction implicitSmoothUnion(std::vector<ImplicitFunction> parts, double blend);

/// Intersection max(a, b) and difference max(a, -b).
ImplicitFunction implicitIntersection(ImplicitFunction a, ImplicitFunction b);
ImplicitFunction implicitDifference(ImplicitFunction a, ImplicitFunction b);

/// A named piece of an implicit model. Several parts may share a name; the element set of
/// that name is then the union of their elements (see labelElementsByPart).
struct ImplicitPart {
  std::string name;
  ImplicitFunction function;
};

/// The smooth union of every part's function (blend width as in implicitSmoothUnion).
ImplicitFunction implicitUnionOfParts(const std::vector<ImplicitPart>& parts, double blend);

}  // namespace asyncfem
