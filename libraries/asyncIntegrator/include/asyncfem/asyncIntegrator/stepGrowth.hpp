// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/integrator/integrator.hpp>

namespace asyncfem {

/// Settings of estimateStepGrowth().
struct StepGrowthOptions {
  /// Krylov vectors k: the estimate costs k calls to step().
  int krylovDimension = 30;
  unsigned seed = 1;  ///< of the random start state
  /// The estimate counts as converged when the relative residual of its Ritz pair is at
  /// most this (see StepGrowthEstimate::residual).
  double tolerance = 1e-3;
};

/// What estimateStepGrowth() found.
struct StepGrowthEstimate {
  /// Largest modulus of the Ritz values: the estimated spectral radius of one step's map
  /// (u_0, v_0) -> (u_1, v_1). Above 1: some state grows by about that factor per step.
  double spectralRadius = 0.0;
  /// |h_{k+1,k}| |e_k^T y| / |theta| for the Ritz pair (theta, y) behind spectralRadius,
  /// in the energy norm: for a normal map, the distance from theta to the nearest
  /// eigenvalue relative to |theta|. 0 when the Krylov space became invariant.
  double residual = 0.0;
  bool converged = false;   ///< residual <= StepGrowthOptions::tolerance
  int steps = 0;            ///< calls to step() made
  int krylovDimension = 0;  ///< Krylov vectors used (fewer than asked if the space became invariant)
  double seconds = 0.0;     ///< wall time of the estimate (the integrator's factorization included)
};

/// Estimates the spectral radius of the linear map T: [u_0; v_0] -> [u_1; v_1] of one
/// step() of integrator (for multirate integrators: one large step) by Arnoldi's method
/// with k = options.krylovDimension vectors, one step() each, in the energy inner product
/// <x, y> = v_x^T M v_y + u_x^T (K + eps M) u_y (K the force model's stiffness at rest,
/// eps = (1e-5 / h)^2 only to make rigid displacements of an unfixed body count):
/// Arnoldi's Ritz values converge first to the outer eigenvalues, and unlike power
/// iteration it resolves the complex pairs of an oscillatory step. The start state is
/// random (options.seed; fixed DOFs zero), its u and v parts of equal energy.
///
/// The integrator must integrate a homogeneous linear system (a LinearForceModel, no
/// external force; homogeneousLinearSystem() makes one), otherwise T is not linear:
/// throws asyncfem::Error. Its state is restored on return (its stats() count the steps).
///
/// What it can miss:
/// - an eigenvalue outside the unit circle that the start state barely excites, or that
///   sits in a cluster the k vectors do not separate: check `converged`, raise k;
/// - the Ritz values are within the numerical range of T in that norm, so for a step
///   that never gains energy (backward Euler, the stable coupling) the estimate is <= 1
///   up to round-off and eps; conversely a radius < 1 says nothing about transient
///   growth: the paper's coupling can multiply the energy by 2-13 in one step while its
///   radius is below 1 (shared design note async-stable-coupling.md).
StepGrowthEstimate estimateStepGrowth(Integrator& integrator, const StepGrowthOptions& options = {});

/// system with its force model replaced by its tangent at rest (a LinearForceModel, the
/// same object when already linear) and no external force: the system whose step map
/// estimateStepGrowth() measures. Mass, damping and fixed DOFs are kept.
DynamicSystem homogeneousLinearSystem(const DynamicSystem& system);

}  // namespace asyncfem
