// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/volumetricMesh/queries.hpp>

namespace asyncfem {

/// A pinhole camera: eye position, the point it looks at, the world direction that
/// appears upwards, and the vertical field of view. Lengths in mesh units.
struct Camera {
  Eigen::Vector3d position = Eigen::Vector3d(0.0, 0.0, 5.0);
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  double verticalFieldOfViewDegrees = 30.0;
};

/// Default direction from the target towards the eye used by fitCamera: in front (+z),
/// somewhat to the right (+x) and above (+y), for y-up scenes.
inline Eigen::Vector3d defaultViewDirection() { return {0.45, 0.35, 1.0}; }

/// The camera looking at box's centre along -viewDirection, placed at the smallest
/// distance at which all eight corners of box project inside the image (aspect = width /
/// height) with the given margin (fraction of the half-width / half-height left free on
/// each side). up must not be parallel to viewDirection (asyncfem::Error otherwise).
Camera fitCamera(const BoundingBox& box, double aspect, const Eigen::Vector3d& viewDirection = defaultViewDirection(),
                 const Eigen::Vector3d& up = Eigen::Vector3d::UnitY(), double verticalFieldOfViewDegrees = 30.0,
                 double margin = 0.08);

/// 4x4 world-to-eye matrix of camera (right-handed, looking down -z; as gluLookAt).
Eigen::Matrix4d viewMatrix(const Camera& camera);
/// 4x4 perspective projection (as gluPerspective) for the camera's field of view,
/// aspect = width / height, and the near and far distances (0 < near < far).
Eigen::Matrix4d projectionMatrix(const Camera& camera, double aspect, double nearDistance, double farDistance);

/// Where the renderer draws world point p in a width x height image: x to the right and
/// y downwards in pixels, (0, 0) the top-left corner of the top-left pixel (pixel (i, j)
/// covers [i, i+1) x [j, j+1)). Valid for points in front of the camera.
Eigen::Vector2d projectToPixel(const Camera& camera, int width, int height, const Eigen::Vector3d& p);

}  // namespace asyncfem
