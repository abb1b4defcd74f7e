// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Geometry>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/render/camera.hpp>
#include <asyncfem/render/renderer.hpp>
#include <cmath>
#include <limits>
#include <numbers>

namespace asyncfem {

namespace {

double tanHalfAngle(double degrees) { return std::tan(0.5 * degrees * std::numbers::pi / 180.0); }

/// 1, 2 or 5 times a power of ten, near x.
double roundLength(double x) {
  const double power = std::pow(10.0, std::floor(std::log10(x)));
  for (const double m : {1.0, 2.0, 5.0}) {
    if (m * power >= 0.7 * x) {
      return m * power;
    }
  }
  return 10.0 * power;
}

}  // namespace

Eigen::Matrix4d viewMatrix(const Camera& camera) {
  const Eigen::Vector3d forward = (camera.target - camera.position).normalized();
  const Eigen::Vector3d side = forward.cross(camera.up).normalized();
  const Eigen::Vector3d up = side.cross(forward);
  Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
  view.block<1, 3>(0, 0) = side.transpose();
  view.block<1, 3>(1, 0) = up.transpose();
  view.block<1, 3>(2, 0) = -forward.transpose();
  view.block<3, 1>(0, 3) = -view.block<3, 3>(0, 0) * camera.position;
  return view;
}

Eigen::Matrix4d projectionMatrix(const Camera& camera, double aspect, double nearDistance, double farDistance) {
  const double f = 1.0 / tanHalfAngle(camera.verticalFieldOfViewDegrees);
  Eigen::Matrix4d projection = Eigen::Matrix4d::Zero();
  projection(0, 0) = f / aspect;
  projection(1, 1) = f;
  projection(2, 2) = (farDistance + nearDistance) / (nearDistance - farDistance);
  projection(2, 3) = 2.0 * farDistance * nearDistance / (nearDistance - farDistance);
  projection(3, 2) = -1.0;
  return projection;
}

Eigen::Vector2d projectToPixel(const Camera& camera, int width, int height, const Eigen::Vector3d& p) {
  // x and y of the projection do not depend on near and far.
  const Eigen::Vector4d clip =
      projectionMatrix(camera, static_cast<double>(width) / height, 1.0, 2.0) * viewMatrix(camera) * p.homogeneous();
  const double ndcX = clip.x() / clip.w();
  const double ndcY = clip.y() / clip.w();
  return {0.5 * (ndcX + 1.0) * width, 0.5 * (1.0 - ndcY) * height};
}

Camera fitCamera(const BoundingBox& box, double aspect, const Eigen::Vector3d& viewDirection, const Eigen::Vector3d& up,
                 double verticalFieldOfViewDegrees, double margin) {
  const Eigen::Vector3d back = viewDirection.normalized();
  const Eigen::Vector3d right = up.cross(back);
  if (!(right.norm() > 1e-9 * up.norm()) || !std::isfinite(right.norm())) {
    throw Error("fitCamera: the up direction is parallel to the view direction (or zero)");
  }
  const Eigen::Vector3d side = right.normalized();
  const Eigen::Vector3d upward = back.cross(side);
  const Eigen::Vector3d center = 0.5 * (box.min + box.max);
  const double halfHeight = tanHalfAngle(verticalFieldOfViewDegrees) * (1.0 - margin);
  const double halfWidth = halfHeight * aspect;
  // Every corner c (relative to the centre) at depth D - back.c must satisfy
  // |side.c| <= halfWidth (D - back.c) and |upward.c| <= halfHeight (D - back.c).
  double distance = 0.0;
  const double diagonal = (box.max - box.min).norm();
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d c = boxCorner(box, corner) - center;
    const double depth = back.dot(c);
    distance = std::max(distance, depth + std::abs(side.dot(c)) / halfWidth);
    distance = std::max(distance, depth + std::abs(upward.dot(c)) / halfHeight);
    distance = std::max(distance, depth + (0.01 * diagonal));
  }
  if (!(distance > 0.0)) {
    distance = 1.0;  // an empty box: any distance shows it
  }
  Camera camera;
  camera.target = center;
  camera.position = center + (distance * back);
  camera.up = up;
  camera.verticalFieldOfViewDegrees = verticalFieldOfViewDegrees;
  return camera;
}

GroundPlane groundAt(const BoundingBox& box, const Eigen::Vector3d& up, double height) {
  const double diagonal = std::max((box.max - box.min).norm(), 1e-12);
  const Eigen::Vector3d center = 0.5 * (box.min + box.max);
  const Eigen::Vector3d n = up.normalized();
  return GroundPlane{center + ((height - n.dot(center)) * n), 4.0 * diagonal, roundLength(diagonal / 6.0), true};
}

GroundPlane groundBelow(const BoundingBox& box, const Eigen::Vector3d& up) {
  const double diagonal = std::max((box.max - box.min).norm(), 1e-12);
  const Eigen::Vector3d n = up.normalized();
  double lowest = std::numeric_limits<double>::infinity();
  for (int corner = 0; corner < 8; ++corner) {
    lowest = std::min(lowest, n.dot(boxCorner(box, corner)));
  }
  return groundAt(box, up, lowest - (0.02 * diagonal));
}

}  // namespace asyncfem
