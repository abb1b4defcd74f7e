// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/problem/loads.hpp>
#include <cmath>

namespace asyncfem {

void Loads::addConstant(const Eigen::VectorXd& force) {
  if (constant_.size() == 0) {
    constant_ = force;
  } else if (constant_.size() == force.size()) {
    constant_ += force;
  } else {
    throw ValidationError("Loads::addConstant: size " + std::to_string(force.size()) + " differs from " +
                          std::to_string(constant_.size()));
  }
}

void Loads::addWindow(VertexLoad load) {
  if (load.vertices.empty() || load.perVertex.isZero(0.0)) return;  // acts on nothing
  if (!(load.start <= load.end)) throw ValidationError("Loads::addWindow: start after end");
  windows_.push_back(std::move(load));
}

void Loads::addTo(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                  Eigen::VectorXd& forces) const {
  if (constant_.size() > 0) forces += constant_;
  for (const VertexLoad& load : windows_) {
    if (!load.active(time)) continue;
    for (const int v : load.vertices) forces.segment<3>(3 * static_cast<Eigen::Index>(v)) += load.perVertex;
  }
  if (contact_) contact_->addForces(time, displacement, velocity, forces);
}

void Loads::addTo(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                  const std::vector<int>& vertices, Eigen::VectorXd& forces) const {
  addVertexLoads(time, vertices, forces);
  if (contact_) contact_->addForces(time, displacement, velocity, forces, &vertices);
}

void Loads::addTo(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                  const std::vector<int>& vertices, const std::vector<int>& rank, int owner, Eigen::VectorXd& forces,
                  VertexJacobian* jacobian) const {
  addVertexLoads(time, vertices, forces);
  if (jacobian != nullptr) jacobian->clear();
  if (contact_) contact_->addForcesOfRank(time, displacement, velocity, vertices, rank, owner, forces, jacobian);
}

void Loads::addVertexLoads(double time, const std::vector<int>& vertices, Eigen::VectorXd& forces) const {
  if (constant_.size() > 0)
    for (const int v : vertices) forces.segment<3>(3 * static_cast<Eigen::Index>(v)) += constant_.segment<3>(3 * v);
  for (const VertexLoad& load : windows_) {
    if (!load.active(time)) continue;
    // Both lists ascending: their common vertices in one pass.
    auto at = vertices.begin();
    for (const int v : load.vertices) {
      at = std::lower_bound(at, vertices.end(), v);
      if (at == vertices.end()) break;
      if (*at == v) forces.segment<3>(3 * static_cast<Eigen::Index>(v)) += load.perVertex;
    }
  }
}

std::vector<double> Loads::breakpoints() const {
  std::vector<double> times;
  for (const VertexLoad& load : windows_) {
    if (std::isfinite(load.start)) times.push_back(load.start);
    if (std::isfinite(load.end)) times.push_back(load.end);
  }
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  return times;
}

double Loads::lastChange() const { return contact_ ? std::numeric_limits<double>::infinity() : lastWindowChange(); }

double Loads::lastWindowChange() const {
  const std::vector<double> times = breakpoints();
  return times.empty() ? 0.0 : std::max(0.0, times.back());
}

Eigen::VectorXd Loads::constantPart(Eigen::Index numDofs) const {
  Eigen::VectorXd constant = constant_.size() > 0 ? constant_ : Eigen::VectorXd::Zero(numDofs);
  for (const VertexLoad& load : windows_) {
    if (std::isfinite(load.end)) continue;
    for (const int v : load.vertices) constant.segment<3>(3 * static_cast<Eigen::Index>(v)) += load.perVertex;
  }
  return constant;
}

}  // namespace asyncfem
