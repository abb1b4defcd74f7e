// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/integrator/integratorOptions.hpp>
#include <memory>
#include <string>

namespace asyncfem {

namespace detail {
class FreeSystem;
class FreeMassSolver;
}  // namespace detail

/// Newmark average-acceleration method (beta = 1/4, gamma = 1/2), the trapezoidal rule
/// for second-order systems: second order accurate, unconditionally stable, no numerical
/// damping. For a linear undamped system without external force it conserves
/// v^T M v / 2 + u^T K u / 2 exactly (up to round-off), which makes it the reference
/// integrator. One step of size h from (u_k, v_k, a_k):
///
///     u_{k+1} = u_k + h v_k + h^2/4 (a_k + a_{k+1})
///     v_{k+1} = v_k + h/2 (a_k + a_{k+1})
///     M a_{k+1} + D v_{k+1} + f_int(u_{k+1}) = f_ext(t_{k+1})
///
/// Linearizing f_int(u_{k+1}) ~ f_int(u_k) + K (u_{k+1} - u_k) with K = K(u_k) and
/// D = alpha M + beta K gives the solve
///
///     (M + h/2 D + h^2/4 K) a_{k+1} = f_ext(t_{k+1}) - f_int(u_k) - D (v_k + h/2 a_k)
///                                     - K (h v_k + h^2/4 a_k),
///
/// exact for linear force models (factored once; refactored only after setTimestep()).
/// Nonlinear models refactor numerically each step and, with options.maxIterations > 1,
/// run Newton on R(a) = M a + D v_{k+1}(a) + f_int(u_{k+1}(a)) - f_ext(t_{k+1}) with
/// J = M + h/2 D + h^2/4 K(u_{k+1}(a)), stopping once |R|_2 <= tolerance * |b_0|_2 (b_0
/// the right-hand side above).
///
/// The acceleration a_k is part of the state: it is computed from M a_0 = f_ext(t) -
/// f_int(u) - D v (one mass factorization, kept) at the first step and whenever
/// setState() changes the state, and taken from the solve afterwards.
class Trapezoidal final : public Integrator {
 public:
  Trapezoidal(DynamicSystem system, double timestep, const IntegratorOptions& options = {});
  ~Trapezoidal() override;

  std::string name() const override { return "trapezoidal"; }
  void step() override;
  /// The non-zeros of the system matrix's factor.
  RunReport report() const override;
  void setTimestep(double timestep) override;
  /// a_k (full, 3n), or empty while it is stale (it is then recomputed from u, v, t).
  Eigen::VectorXd internalState() const override;
  void setInternalState(const Eigen::VectorXd& state) override;

  const IntegratorOptions& options() const { return options_; }
  /// a_k (full, 3n), consistent with the current state; computes it if it is stale.
  const Eigen::VectorXd& acceleration();
  int lastIterations() const { return lastIterations_; }
  /// Relative Newton residual after the last step, -1 when not evaluated.
  double lastRelativeResidual() const { return lastRelativeResidual_; }

 protected:
  void stateChanged() override { accelerationStale_ = true; }

 private:
  void computeAcceleration();
  void assembleAndFactor();
  /// rhs_ = the linearized step's right-hand side at u_k (Eq. A1t), refactoring first for
  /// nonlinear models (and for linear ones after setTimestep).
  void linearizedRightHandSide();
  /// Newton iterations after the linearized step: returns how many were taken in all.
  int newtonIterations(double rhsNorm);

  IntegratorOptions options_;
  std::unique_ptr<detail::FreeSystem> free_;
  std::unique_ptr<detail::FreeMassSolver> massSolver_;
  bool linear_ = false;
  bool factorizationStale_ = true;
  bool accelerationStale_ = true;
  int lastIterations_ = 0;
  double lastRelativeResidual_ = -1.0;
  Eigen::VectorXd acceleration_;  // full
  Eigen::VectorXd u_, v_, a_, force_, internal_, rhs_, work_, newA_;
  Eigen::VectorXd fullForce_, fullU_, fullV_, fullA_;
};

}  // namespace asyncfem
