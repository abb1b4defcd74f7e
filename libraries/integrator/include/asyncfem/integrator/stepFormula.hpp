// SPDX-License-Identifier: BSD-3-Clause
#pragma once

// The step formulas of the implicit single-rate schemes, written once: the weights of the
// system matrix and the recipe of the right-hand side of one linearized step of
//   M a + D v + f_int(u) = f_ext(t),  D = alpha M + beta K,
// for backward Euler and the trapezoidal rule. Every backend (the CHOLMOD integrators, the
// large-step block L of the asynchronous integrator, the PETSc backend) takes its
// coefficients from here and applies them with its own vector type. The equations are
// (A1) and (A1t) of docs/asynchronous-integrator.md, section "Method".

namespace asyncfem::stepFormula {

/// A linear combination of the mass and the stiffness matrix: mass * M + stiffness * K.
struct MatrixWeights {
  double mass = 1.0;
  double stiffness = 0.0;
};

/// The right-hand side of one linearized step, with f_int and K at the step's start u_k:
///   b = scale * ( f_ext(t_{k+1}) - f_int(u_k) - K w_K - alpha M w_M ),
///   w_K = velocityStiffness v_k + accelerationStiffness a_k,
///   w_M = v_k + accelerationMass a_k.
/// For a linear model f_int(u_k) = K u_k, so backends fold it into the one product
/// K (u_k + w_K). The solution of (system matrix) x = b is the step's unknown (Unknown).
struct RightHandSide {
  double scale = 1.0;
  double velocityStiffness = 0.0;
  double accelerationStiffness = 0.0;
  double accelerationMass = 0.0;
};

/// Backward Euler, Eq. (A1): (M + h D + h^2 K) dv = h (f_ext(t_{k+1}) - f_int(u_k) - D v_k -
/// h K v_k); v_{k+1} = v_k + dv, u_{k+1} = u_k + h v_{k+1}. h in seconds, alpha in 1/s,
/// beta in s.
namespace backwardEuler {
/// (1 + h alpha) M + (h beta + h^2) K.
inline MatrixWeights systemMatrix(double h, double alpha, double beta) {
  return {1.0 + (h * alpha), (h * beta) + (h * h)};
}
/// scale h, w_K = (beta + h) v_k, w_M = v_k.
inline RightHandSide rightHandSide(double h, double beta) { return {h, beta + h, 0.0, 0.0}; }
}  // namespace backwardEuler

/// The trapezoidal rule, Eq. (A1t), for the new acceleration a_{k+1}:
/// (M + h/2 D + h^2/4 K) a_{k+1} = f_ext(t_{k+1}) - f_int(u_k) - D (v_k + h/2 a_k) -
/// K (h v_k + h^2/4 a_k); u_{k+1} = u_k + h v_k + h^2/4 (a_k + a_{k+1}),
/// v_{k+1} = v_k + h/2 (a_k + a_{k+1}).
namespace trapezoidal {
/// (1 + h alpha / 2) M + (h beta / 2 + h^2 / 4) K.
inline MatrixWeights systemMatrix(double h, double alpha, double beta) {
  return {1.0 + (0.5 * h * alpha), (0.5 * h * beta) + (0.25 * h * h)};
}
/// scale 1, w_K = (beta + h) v_k + (h beta / 2 + h^2 / 4) a_k, w_M = v_k + h/2 a_k.
inline RightHandSide rightHandSide(double h, double beta) {
  return {1.0, beta + h, (0.5 * h * beta) + (0.25 * h * h), 0.5 * h};
}
/// Weight of a_k + a_{k+1} in the displacement update (h^2 / 4) and in the velocity update (h / 2).
inline double displacementWeight(double h) { return 0.25 * h * h; }
inline double velocityWeight(double h) { return 0.5 * h; }
}  // namespace trapezoidal

}  // namespace asyncfem::stepFormula
