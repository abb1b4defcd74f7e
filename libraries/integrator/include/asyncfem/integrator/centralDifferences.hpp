// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/integrator/integratorOptions.hpp>
#include <memory>
#include <string>

namespace asyncfem {

namespace detail {
class ExplicitCore;
}

/// Explicit central differences in the half-step velocity form used by explicit FEM
/// codes (Belytschko, Liu & Moran, "Nonlinear Finite Elements", Box 6.1). One step of
/// size h from (u_k, v_k, a_k):
///
///     v_{k+1/2} = v_k + h/2 a_k
///     u_{k+1}   = u_k + h v_{k+1/2}
///     a_{k+1}   = M^{-1} ( f_ext(t_{k+1}) - f_int(u_{k+1}) - D v_{k+1/2} )
///     v_{k+1}   = v_{k+1/2} + h/2 a_{k+1}
///
/// Without damping this is exactly u_{k+1} - 2 u_k + u_{k-1} = h^2 a_k, second order.
/// Damping uses the velocity lagged by half a step (v_{k+1/2}) so the step stays explicit
/// for any D = alpha M + beta K; this is first order in the damping term, the standard
/// trade-off of explicit codes. a_0 uses D v_0.
///
/// M is factored once: a diagonal (lumped) mass is inverted entry-wise, a consistent
/// one gets a sparse Cholesky (options.solver). The method is stable for
/// h <= 2 / omega_max (undamped bound); omega_max comes from options.maxFrequency when
/// given (e.g. estimateMaxFrequency(mesh, massType), a rigorous bound), else from
/// estimateMaxFrequency(K, M) on the free matrices (K at rest for nonlinear models). The
/// constructor and setTimestep() throw asyncfem::ValidationError for a larger h unless
/// options.force is set.
class CentralDifferences final : public Integrator {
 public:
  CentralDifferences(DynamicSystem system, double timestep, const IntegratorOptions& options = {});
  ~CentralDifferences() override;

  std::string name() const override { return "central-differences"; }
  void step() override;
  void setTimestep(double timestep) override;
  /// a_k on the free DOFs, or empty while it is stale (recomputed from u, v, t).
  Eigen::VectorXd internalState() const override;
  void setInternalState(const Eigen::VectorXd& state) override;
  /// 2 / omega_max.
  double stableTimestepEstimate() const override;
  /// omega_max used for the check (rad per time unit).
  double maxFrequency() const;

 protected:
  void stateChanged() override { accelerationStale_ = true; }

 private:
  std::unique_ptr<detail::ExplicitCore> core_;
  bool accelerationStale_ = true;
  Eigen::VectorXd acceleration_;  // free
  Eigen::VectorXd u_, v_, fullU_, fullV_;
};

}  // namespace asyncfem
