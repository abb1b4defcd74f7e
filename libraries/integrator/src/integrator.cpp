// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <cmath>
#include <limits>
#include <string>

namespace asyncfem {

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

namespace {
const char* coordinateName(int c) { return c == 0 ? "x" : (c == 1 ? "y" : "z"); }

void checkFinite(const Eigen::VectorXd& vector, const char* what, double time, const std::string& integratorName) {
  for (Eigen::Index i = 0; i < vector.size(); ++i) {
    if (!std::isfinite(vector[i])) {
      const int dof = static_cast<int>(i);
      throw NumericalError(integratorName + ": non-finite " + what + " (" + std::to_string(vector[i]) +
                               ") in the step to time " + std::to_string(time) + " at DOF " + std::to_string(dof) +
                               " (vertex " + std::to_string(dof / 3) + ", coordinate " + coordinateName(dof % 3) +
                               "); the state was left at the start of the step",
                           NumericalErrorLocation{time, -1, -1, dof, dof / 3, -1, {}});
    }
  }
}
}  // namespace

void Integrator::commitStep(Eigen::VectorXd& displacement, Eigen::VectorXd& velocity) {
  const double time = stepEndTime();
  checkFinite(displacement, "displacement", time, name());
  checkFinite(velocity, "velocity", time, name());
  displacement_.swap(displacement);
  velocity_.swap(velocity);
  advanceTime();
  ++stats_.steps;
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
