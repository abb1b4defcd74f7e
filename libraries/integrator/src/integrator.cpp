// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <cmath>
#include <limits>
#include <string>

namespace asyncfem {

void DynamicSystem::validate() const {
  if (!forceModel) throw ValidationError("dynamic system has no force model");
  const int n = forceModel->numDofs();
  if (mass.rows() != n || mass.cols() != n) {
    throw ValidationError("mass matrix is " + std::to_string(mass.rows()) + " x " + std::to_string(mass.cols()) +
                          " but the force model has " + std::to_string(n) + " DOFs");
  }
  if (freeDofs.numDofs() != n) {
    throw ValidationError("free-DOF map covers " + std::to_string(freeDofs.numDofs()) + " DOFs, expected " +
                          std::to_string(n));
  }
  if (!(rayleighMass >= 0.0) || !(rayleighStiffness >= 0.0) || !std::isfinite(rayleighMass) ||
      !std::isfinite(rayleighStiffness)) {
    throw ValidationError("Rayleigh damping coefficients must be finite and >= 0 (alpha " +
                          std::to_string(rayleighMass) + ", beta " + std::to_string(rayleighStiffness) + ")");
  }
}

Integrator::Integrator(DynamicSystem system, double timestep) : system_(std::move(system)) {
  system_.validate();
  system_.mass.makeCompressed();
  displacement_ = Eigen::VectorXd::Zero(system_.numDofs());
  velocity_ = Eigen::VectorXd::Zero(system_.numDofs());
  Integrator::setTimestep(timestep);
}

double Integrator::stableTimestepEstimate() const { return std::numeric_limits<double>::infinity(); }

void Integrator::setTimestep(double timestep) {
  if (!(timestep > 0.0) || !std::isfinite(timestep)) {
    throw TimestepError("timestep must be positive and finite (got " + std::to_string(timestep) + ")");
  }
  timestep_ = timestep;
  restartTimeGrid();
}

void Integrator::restartTimeGrid() {
  // Keep t = k h exactly when the time is on the grid (a run's start, a checkpoint's time),
  // so that a resumed run evaluates loads at the very times an uninterrupted one does.
  const double steps = std::round(time_ / timestep_);
  if (std::abs(steps) < 1e15 && steps * timestep_ == time_) {
    timeOrigin_ = 0.0;
    stepIndex_ = static_cast<long long>(steps);
  } else {
    timeOrigin_ = time_;
    stepIndex_ = 0;
  }
}

double Integrator::stepEndTime() const { return timeOrigin_ + (static_cast<double>(stepIndex_ + 1) * timestep_); }

void Integrator::advanceTime() {
  time_ = stepEndTime();
  ++stepIndex_;
}

void Integrator::setState(const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity, double time) {
  if (displacement.size() != system_.numDofs() || velocity.size() != system_.numDofs()) {
    throw Error("setState: state vectors must have " + std::to_string(system_.numDofs()) + " entries");
  }
  displacement_ = displacement;
  velocity_ = velocity;
  zeroFixed(displacement_);
  zeroFixed(velocity_);
  time_ = time;
  restartTimeGrid();
  stateChanged();
}

Eigen::VectorXd Integrator::internalState() const { return {}; }

void Integrator::setInternalState(const Eigen::VectorXd& state) {
  if (state.size() != 0) {
    throw Error(name() + ": setInternalState: this integrator keeps no state beyond u, v and t (got " +
                std::to_string(state.size()) + " values)");
  }
}

double Integrator::mechanicalEnergy() const {
  const double kinetic = 0.5 * velocity_.dot(system_.mass * velocity_);
  return kinetic + system_.forceModel->elasticEnergy(displacement_);
}

void Integrator::evaluateExternalForce(double time, Eigen::VectorXd& forces) const {
  forces.setZero(system_.numDofs());
  if (system_.externalForce) system_.externalForce(time, displacement_, velocity_, forces);
}

void Integrator::zeroFixed(Eigen::VectorXd& full) const {
  const std::vector<int>& map = system_.freeDofs.fullToFree();
  for (std::size_t i = 0; i < map.size(); ++i) {
    if (map[i] < 0) full[static_cast<Eigen::Index>(i)] = 0.0;
  }
}

}  // namespace asyncfem
