// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>

/// Signs of orientation determinants, exact for finite coordinates whose products neither
/// overflow nor underflow (docs/collision.md, "Triangle-triangle intersection").
namespace asyncfem::detail {

/// Sign (-1, 0, +1) of det[b - a, c - a] (2D): +1 when a, b, c turn counter-clockwise.
int orientation2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c);

/// Sign (-1, 0, +1) of det[b - a, c - a, d - a] = (b - a) . ((c - a) x (d - a)): zero when the
/// four points are coplanar, opposite for d on opposite sides of the plane of a, b, c.
int orientation3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                  const Eigen::Vector3d& d);

}  // namespace asyncfem::detail
