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

/// Symplectic (semi-implicit) Euler, first order, explicit. One step of size h:
///
///     v_{k+1} = v_k + h M^{-1} ( f_ext(t_k) - f_int(u_k) - D v_k )
///     u_{k+1} = u_k + h v_{k+1}
///
/// For an undamped linear mode of frequency omega the step matrix has trace
/// 2 - h^2 omega^2 and determinant 1, so it is stable for h <= 2 / omega_max, the same
/// limit as central differences; the same estimate and check apply (see
/// CentralDifferences), and M is factored once the same way.
class SymplecticEuler final : public Integrator {
 public:
  SymplecticEuler(DynamicSystem system, double timestep, const IntegratorOptions& options = {});
  ~SymplecticEuler() override;

  std::string name() const override { return "symplectic-euler"; }
  void step() override;
  void setTimestep(double timestep) override;
  double stableTimestepEstimate() const override;
  double maxFrequency() const;

 private:
  std::unique_ptr<detail::ExplicitCore> core_;
  Eigen::VectorXd u_, v_, a_, fullU_, fullV_;
};

}  // namespace asyncfem
