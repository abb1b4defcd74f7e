// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/asyncIntegrator/asyncOptions.hpp>

// The scalar coefficients that couple one fast region to L inside a large step: pure
// math, no matrices. Equations (A5)-(A6), (A9)-(A11) of docs/asynchronous-integrator.md.
namespace asyncfem::detail {

/// The coefficients of the coupling blocks of one fast region with ratio m, for
/// r, i = 1..m (entry r - 1, i - 1):
///   B_r = bM[r] M^{SI} + bD[r] D^{SI} + bK[r] K^{SI}     (S row r, coefficient of Y)
///   E_i = eM[i] M^{IS} + eD[i] D^{IS} + eK[i] K^{IS}     (L row, coefficient of X_i)
/// and interfaceWeight = (1 - theta) hL^2, theta = (m + 1) / (2m), the share of the
/// interface elements' stiffness taken out of A^L (Eq. A11; 0 for the paper's coupling).
/// Units: bM, eM dimensionless; bD, eD seconds; bK, eK, interfaceWeight seconds^2.
struct CouplingCoefficients {
  Eigen::VectorXd bM, bD, bK, eM, eD, eK;
  double interfaceWeight = 0.0;
};

/// The coefficients for a region with m = ratio substeps per large step hL (seconds):
/// Eqs. (A5)-(A6) for AsyncCoupling::paper, (A9)-(A11) for AsyncCoupling::stable.
/// m = 1 gives single-rate backward Euler's blocks, Eq. (A1), for both couplings.
CouplingCoefficients couplingCoefficients(AsyncCoupling coupling, int ratio, double largeStep);

}  // namespace asyncfem::detail
