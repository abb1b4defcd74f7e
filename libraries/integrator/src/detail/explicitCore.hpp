// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/integrator/integratorOptions.hpp>
#include <string>

#include "detail/freeSystem.hpp"

namespace asyncfem::detail {

/// What central differences and symplectic Euler share: the free matrices, the mass
/// solve, the omega_max estimate and the timestep check, and the acceleration
/// a = M^{-1} (f_ext(t) - f_int(u) - D v) on the free DOFs.
class ExplicitCore {
 public:
  ExplicitCore(const DynamicSystem& system, const IntegratorOptions& options, IntegratorStats& stats);

  /// 2 / omega_max (+inf without stiffness).
  double stableTimestep() const;
  double maxFrequency() const { return maxFrequency_; }
  /// Throws asyncfem::ValidationError if h exceeds stableTimestep() and force is off.
  void checkTimestep(double timestep, const std::string& methodName) const;

  /// a (free) from the full state (fullDisplacement, fullVelocity) at time t; damping
  /// uses dampingVelocity (free), which the caller chooses (v_k or a lagged v).
  void acceleration(const DynamicSystem& system, double time, const Eigen::VectorXd& fullDisplacement,
                    const Eigen::VectorXd& fullVelocity, const Eigen::VectorXd& dampingVelocity,
                    Eigen::VectorXd& acceleration, IntegratorStats& stats);

 private:
  FreeSystem free_;
  FreeMassSolver massSolver_;
  bool linear_ = false;
  bool force_ = false;
  double maxFrequency_ = 0.0;
  Eigen::VectorXd fullForce_, rhs_, u_, internal_;
};

}  // namespace asyncfem::detail
