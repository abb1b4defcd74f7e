// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/integrator/symplecticEuler.hpp>

#include "detail/explicitCore.hpp"

namespace asyncfem {

SymplecticEuler::SymplecticEuler(DynamicSystem system, double timestep, const IntegratorOptions& options)
    : Integrator(std::move(system), timestep), core_(std::make_unique<detail::ExplicitCore>(system_, options, stats_)) {
  core_->checkTimestep(timestep_, "symplectic Euler");
}

SymplecticEuler::~SymplecticEuler() = default;

double SymplecticEuler::stableTimestepEstimate() const { return core_->stableTimestep(); }
double SymplecticEuler::maxFrequency() const { return core_->maxFrequency(); }

void SymplecticEuler::setTimestep(double timestep) {
  if (core_) core_->checkTimestep(timestep, "symplectic Euler");
  Integrator::setTimestep(timestep);
}

void SymplecticEuler::step() {
  const double h = timestep_;
  const FreeDofs& dofs = system_.freeDofs;
  detail::restrictTo(dofs, displacement_, u_);
  detail::restrictTo(dofs, velocity_, v_);
  // a_k = M^{-1} (f_ext(t_k) - f_int(u_k) - D v_k); v_{k+1} = v_k + h a_k; u_{k+1} = u_k + h v_{k+1}
  core_->acceleration(system_, time_, displacement_, velocity_, v_, a_, stats_);
  v_ += h * a_;
  u_ += h * v_;
  detail::expandTo(dofs, u_, fullU_);
  detail::expandTo(dofs, v_, fullV_);
  commitStep(fullU_, fullV_);
}

}  // namespace asyncfem
