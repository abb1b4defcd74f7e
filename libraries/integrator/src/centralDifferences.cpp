// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/centralDifferences.hpp>
#include <string>

#include "detail/explicitCore.hpp"

namespace asyncfem {

CentralDifferences::CentralDifferences(DynamicSystem system, double timestep, const IntegratorOptions& options)
    : Integrator(std::move(system), timestep), core_(std::make_unique<detail::ExplicitCore>(system_, options, stats_)) {
  core_->checkTimestep(timestep_, "central differences");
}

CentralDifferences::~CentralDifferences() = default;

double CentralDifferences::stableTimestepEstimate() const { return core_->stableTimestep(); }
double CentralDifferences::maxFrequency() const { return core_->maxFrequency(); }

void CentralDifferences::setTimestep(double timestep) {
  // Check first so that a refused timestep leaves the integrator unchanged.
  if (core_) core_->checkTimestep(timestep, "central differences");
  Integrator::setTimestep(timestep);
}

Eigen::VectorXd CentralDifferences::internalState() const {
  if (accelerationStale_) return {};
  return acceleration_;
}

void CentralDifferences::setInternalState(const Eigen::VectorXd& state) {
  if (state.size() == 0) {
    accelerationStale_ = true;
    return;
  }
  const int freeDofs = system_.freeDofs.numFree();
  if (state.size() != freeDofs || !state.allFinite()) {
    throw Error("central-differences: setInternalState: expected the acceleration on the free DOFs, " +
                std::to_string(freeDofs) + " finite values (got " + std::to_string(state.size()) + ")");
  }
  acceleration_ = state;
  accelerationStale_ = false;
}

void CentralDifferences::step() {
  const double h = timestep_;
  const FreeDofs& dofs = system_.freeDofs;
  detail::restrictTo(dofs, displacement_, u_);
  detail::restrictTo(dofs, velocity_, v_);
  if (accelerationStale_) {
    core_->acceleration(system_, time_, displacement_, velocity_, v_, acceleration_, stats_);
    accelerationStale_ = false;
  }
  // v_{k+1/2} = v_k + h/2 a_k, u_{k+1} = u_k + h v_{k+1/2}
  v_ += (0.5 * h) * acceleration_;
  u_ += h * v_;
  detail::expandTo(dofs, u_, fullU_);
  detail::expandTo(dofs, v_, fullV_);
  Eigen::VectorXd newAcceleration;
  core_->acceleration(system_, stepEndTime(), fullU_, fullV_, v_, newAcceleration, stats_);
  // v_{k+1} = v_{k+1/2} + h/2 a_{k+1}
  v_ += (0.5 * h) * newAcceleration;
  detail::expandTo(dofs, v_, fullV_);
  commitStep(fullU_, fullV_);
  acceleration_.swap(newAcceleration);
}

}  // namespace asyncfem
