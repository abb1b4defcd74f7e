// SPDX-License-Identifier: BSD-3-Clause
// The quick set-up: L's system solved by conjugate gradients on the whole single-rate
// factor until the iterations have cost the rebuild they put off (AsyncOptions::KeptFactors::quickSetUp;
// docs/asynchronous-integrator.md, "Quick set-up", Eq. Q4).
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <cmath>
#include <string>

#include "detail/flopPrices.hpp"
#include "detail/multirateSupport.hpp"
#include "detail/wholeSystemFactor.hpp"
#include "twoLevelStepSolver.hpp"

namespace asyncfem {

using detail::TwoLevelStepSolver;

using detail::FastRegion;
using detail::kBlockedFlopWeight;
using detail::kQuickBlockedFlopWeight;
using detail::kSolveCallFlops;
using SparseMatrix = Eigen::SparseMatrix<double>;

namespace {
/// Most doubles the quick set-up's deflation directions and their products may hold (64 MiB).
constexpr double kMaxDeflationEntries = 8.0 * 1024 * 1024;
/// Flop prices of the quick set-up's rent-or-buy rule (Eq. Q4).
struct QuickCosts {
  double iteration = 0.0;   ///< one preconditioner solve and one product with H^{LL*}
  double exactSolve = 0.0;  ///< what a step with a factor of H^{LL*} spends instead (one solve)
  double rebuild = 0.0;     ///< Z and the factor of H^{LL*}
};

QuickCosts quickCosts(const std::vector<FastRegion>& regions, const SparseMatrix& largeSystem,
                      const RegionPartition& partition, const detail::WholeSystemFactor& whole) {
  QuickCosts costs;
  costs.exactSolve = whole.solveFlops() + kSolveCallFlops;
  costs.iteration = costs.exactSolve + 2.0 * static_cast<double>(largeSystem.nonZeros());
  costs.rebuild = kQuickBlockedFlopWeight * whole.factorFlops();
  for (std::size_t i = 0; i < regions.size(); ++i) {
    const FastRegion& rb = regions[i];
    // A forward substitution: m_i solves with A^S and m_i products with G; Z is |I_i| of
    // them, in blocks of columns.
    const double substitution = rb.substitutionFlops;
    costs.iteration += substitution + rb.ratio * kSolveCallFlops;
    costs.rebuild += kQuickBlockedFlopWeight * substitution *
                     static_cast<double>(partition.interfaceDofs(static_cast<int>(i)).size());
  }
  return costs;
}

}  // namespace

// Quick set-up: the whole single-rate system's factor, made once per hL (nonlinear forces:
// from the first tangent, then kept as a preconditioner) and shared by every partition.
void TwoLevelStepSolver::borrowWholeFactor() {
  Impl& d = *impl_;
  if (!whole_) whole_ = std::make_unique<detail::WholeSystemFactor>();
  if (!whole_->factoredFor(timestep())) {
    Stopwatch factor;
    whole_->factor(system_.mass, d.stiffness, system_.freeDofs.freeToFull(), timestep(), system_.rayleighMass,
                   system_.rayleighStiffness, stats_);
    const double seconds = factor.stop();
    stats_.factorizationSeconds += seconds;
    if (d.build.settingUp) runStats_.setupSchurSeconds += seconds;
  }
  if (!d.schur.borrowing()) d.schur.borrow(whole_.get(), partition_.largeDofs());
  if (!d.model.linear) d.schur.forgetDirections();  // a new tangent: H^{LL*} changed
}

// Quick set-up (Eqs. Q1-Q3): deflated conjugate gradients on H^{LL*}, preconditioned by the
// Schur complement of the whole single-rate system on L. Exact with no region (H^{LL*} =
// A). The flops beyond one solve are what the missing factor costs; once they add up to the
// rebuild's price, or the iterations do not converge, Z and H^{LL*} are built (the rent-
// or-buy rule: about twice what knowing the partition's lifetime would have cost at most).
void TwoLevelStepSolver::solveOnWholeFactor() {
  Impl& d = *impl_;
  if (partition_.numRegions() == 0 && !d.contact.blocksInMatrix()) {
    d.schur.solve(d.rhsSchur, d.Y);
    return;
  }
  const auto apply = [this](const Eigen::VectorXd& y, Eigen::VectorXd& out) { applySchur(y, out); };
  // H^{LL*} - (Schur complement of A) lies on I x I, so the iterations after the first
  // live in a space of at most |I| dimensions: that many kept directions (64 MiB at most)
  // deflate it whole.
  const double perDirection = 2.0 * static_cast<double>(d.rhsSchur.size());
  const int keep = static_cast<int>(std::min(runStats_.interfaceDofs + 16.0, kMaxDeflationEntries / perDirection));
  const detail::SchurSolver::Refinement result =
      d.schur.solveDeflated(d.rhsSchur, d.Y, apply, options_.keptFactors.quickSetUpIterations,
                            options_.keptFactors.laggedSchurTolerance, keep);
  runStats_.quickIterations += result.iterations;
  if (result.converged) {
    ++runStats_.quickSteps;
    runStats_.largestQuickResidual = std::max(runStats_.largestQuickResidual, result.residual);
    const QuickCosts costs = quickCosts(d.regions, d.largeSystem, partition_, *whole_);
    const double deflation = 2.0 * static_cast<double>(d.schur.keptDirections()) * static_cast<double>(d.Y.size());
    d.quickPath.extraFlops +=
        result.iterations * (costs.iteration + 2.0 * deflation) + 3.0 * deflation - costs.exactSolve;
    if (d.quickPath.extraFlops < costs.rebuild || !options_.keptFactors.quickSetUpRebuild) return;
  }
  Stopwatch rebuild;
  d.quickPath.active = false;
  fullSchurRebuild();
  ++runStats_.quickEnds;
  runStats_.rebuildSeconds += rebuild.stop();
  if (!result.converged) d.schur.solve(d.rhsSchur, d.Y);
}

}  // namespace asyncfem
