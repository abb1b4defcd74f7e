// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/contact/meshObstacle.hpp>
#include <asyncfem/core/error.hpp>
#include <cmath>
#include <string>

namespace asyncfem {

RigidPath::RigidPath(std::vector<RigidKey> keys) : keys_(std::move(keys)) {
  if (keys_.size() < 2) {
    throw ValidationError("a moving obstacle's path needs at least two keys (got " + std::to_string(keys_.size()) +
                          ")");
  }
  for (std::size_t k = 0; k < keys_.size(); ++k) {
    RigidKey& key = keys_[k];
    const bool finite = std::isfinite(key.time) && key.translation.allFinite() && key.rotation.coeffs().allFinite();
    if (!finite || !(key.rotation.norm() > 0.0)) {
      throw ValidationError("path key " + std::to_string(k) + " has a non-finite time, translation or rotation");
    }
    key.rotation.normalize();
    if (k > 0 && !(key.time > keys_[k - 1].time)) {
      throw ValidationError("path key " + std::to_string(k) + ": times must increase (key " + std::to_string(k - 1) +
                            " is at " + std::to_string(keys_[k - 1].time) + ", this one at " +
                            std::to_string(key.time) + ")");
    }
  }
}

void RigidPath::placement(double t, Eigen::Matrix3d& rotation, Eigen::Vector3d& translation,
                          Eigen::Vector3d& angularVelocity, Eigen::Vector3d& velocity) const {
  angularVelocity.setZero();
  velocity.setZero();
  if (t <= keys_.front().time || t >= keys_.back().time) {
    const RigidKey& held = t <= keys_.front().time ? keys_.front() : keys_.back();
    rotation = held.rotation.toRotationMatrix();
    translation = held.translation;
    return;
  }
  // The segment [k, k+1] holding t (keys sorted by time).
  const auto after =
      std::upper_bound(keys_.begin(), keys_.end(), t, [](double time, const RigidKey& key) { return time < key.time; });
  const RigidKey& start = *(after - 1);
  const RigidKey& end = *after;
  const double duration = end.time - start.time;
  const double fraction = (t - start.time) / duration;
  // The turn from start to end in world axes, the shorter way round.
  Eigen::Quaterniond turn = end.rotation * start.rotation.conjugate();
  if (turn.w() < 0.0) turn.coeffs() = -turn.coeffs();
  const Eigen::AngleAxisd axisAngle(turn);
  rotation = (Eigen::AngleAxisd(fraction * axisAngle.angle(), axisAngle.axis()) * start.rotation).toRotationMatrix();
  translation = start.translation + fraction * (end.translation - start.translation);
  angularVelocity = (axisAngle.angle() / duration) * axisAngle.axis();
  velocity = (end.translation - start.translation) / duration;
}

}  // namespace asyncfem
