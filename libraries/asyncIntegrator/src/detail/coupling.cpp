// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/asyncIntegrator/detail/coupling.hpp>

namespace asyncfem::detail {

CouplingCoefficients couplingCoefficients(AsyncCoupling coupling, int ratio, double largeStep) {
  const int m = ratio;
  const double hL = largeStep;
  const double hS = hL / m;
  CouplingCoefficients c;
  for (Eigen::VectorXd* v : {&c.bM, &c.bD, &c.bK, &c.eM, &c.eD, &c.eK}) v->setZero(m);
  for (int r = 1; r <= m; ++r) {
    const Eigen::Index k = r - 1;
    if (coupling == AsyncCoupling::paper) {
      // L's velocity interpolated linearly, u^L_r = u^L_0 + r hS v^L_r; the interface force
      // on L taken at the end of the step (Eqs. A5, A6).
      c.bM[k] = 1.0 / m;
      c.bD[k] = r * hS / m;
      c.bK[k] = double(r) * r * hS * hS / m;
      c.eK[k] = hL * hS;
      if (r == m) {
        c.eM[k] = 1.0;
        c.eD[k] = hL;
      }
    } else {
      // L at its end-of-step velocity from the first substep on, the interface elements'
      // force on L averaged over the substeps (Eqs. A9, A10).
      c.bM[k] = r == 1 ? 1.0 : 0.0;
      c.bD[k] = hS;
      c.bK[k] = r * hS * hS;
      c.eD[k] = hS;
      c.eK[k] = (m - r + 1) * hS * hS;
      if (r == m) c.eM[k] = 1.0;
    }
  }
  if (coupling == AsyncCoupling::stable) {
    const double theta = (m + 1.0) / (2.0 * m);
    c.interfaceWeight = (1.0 - theta) * hL * hL;
  }
  return c;
}

}  // namespace asyncfem::detail
