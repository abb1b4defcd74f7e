// SPDX-License-Identifier: BSD-3-Clause
// The run summary of AsyncBackwardEuler (RunReport lines and resume caveats).
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <cmath>
#include <cstdio>
#include <string>

#include "detail/multirateSupport.hpp"
#include "stepSolvers.hpp"
#include "twoLevelStepSolver.hpp"

namespace asyncfem {

namespace {

/// A tolerance as a reader writes it (1e-10, not to_string's 0.000000).
std::string shortNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", value);
  return text;
}

}  // namespace

namespace {

// The summary's lines on implicit contact (none without contact steps).
void appendContactLines(const AsyncRunStats& r, int contactIterations, std::vector<std::string>& lines) {
  if (r.contactSteps == 0) return;
  lines.push_back(detail::contactLine(
      r, "", "iterations", contactIterations,
      "A^S refactored " + std::to_string(r.contactRegionFactorizations) + " times for its contact blocks" +
          (r.contactPairBlocksDropped > 0 ? "; " + std::to_string(r.contactPairBlocksDropped) +
                                                " steps stalled with the fast regions' surface-pair blocks and went on "
                                                "without them"
                                          : std::string())));
  char line[256];
  if (r.contactFreeSteps == 0 && r.contactScreenedSteps == 0) return;
  std::snprintf(line, sizeof(line),
                "async implicit contact: %lld of those steps certified free of contact after one solve (end states "
                "only, Eq. C6); %lld started with no substep state to visit (predicted states clear, Eq. C7)",
                r.contactFreeSteps, r.contactScreenedSteps);
  lines.emplace_back(line);
}

}  // namespace

RunReport AsyncBackwardEuler::report() const {
  RunReport report;
  report.factorNonZeros = factorNonZeros();
  report.mayGainEnergy = options_.coupling == AsyncCoupling::paper;
  const auto addCaveat = [&report](const std::string& caveat) {
    if (!report.resumeCaveat.empty()) report.resumeCaveat += "; ";
    report.resumeCaveat += caveat;
  };
  if (options_.keptFactors.laggedSchur && !system_.forceModel->isLinear() &&
      stepSolver() == AsyncStepSolver::structuredSchur) {
    addCaveat(
        "laggedSchur: the H^{LL*} factor kept as preconditioner is not in the checkpoint, so the resumed run "
        "refactors at its first step; its frames match an uninterrupted run to about the Schur tolerance (" +
        shortNumber(options_.keptFactors.laggedSchurTolerance) + "), not bit for bit");
  }
  if (options_.keptFactors.quickSetUp && options_.coupling == AsyncCoupling::stable &&
      options_.method == AsyncSolveMethod::structured) {
    addCaveat(
        "quickSetUp: whether the partition still solved on the whole system's factor is not in the checkpoint, "
        "so the resumed run starts on it again; its frames match an uninterrupted run to about the Schur "
        "tolerance (" +
        shortNumber(options_.keptFactors.laggedSchurTolerance) + "), not bit for bit");
  }
  if (system_.externalForceJacobian && linearizesExternalForce()) {
    addCaveat(
        "implicit contact: the contact blocks kept in the regions' A^S (and the factors built with them) are not in "
        "the checkpoint, so the resumed run's contact iterations start from other matrices; its frames match an "
        "uninterrupted run to about the contact tolerance (" +
        shortNumber(options_.contact.tolerance) + "), not bit for bit");
  }
  if (policy_) {
    addCaveat(
        "run-time regions: the partition in use and how long it has been kept are not in the checkpoint, so the "
        "resumed run chooses its regions afresh from the resumed state and its frames can differ from an "
        "uninterrupted run's (by as much as two partitions' trajectories differ)");
  }
  std::vector<std::string>& lines = report.lines;
  if (!regionNote_.empty()) lines.push_back("regions " + regionNote_);
  const AsyncStepSolver kind = stepSolver();
  lines.push_back("async step solver: " + toString(kind) +
                  (kind == AsyncStepSolver::hierarchy ? " (regions that touch or nest, or on request)"
                                                      : " (each region coupled only to L)"));
  solver_->reportLines(lines);
  if (policy_) appendRepartitionLines(repartitions_, lines);
  return report;
}

void detail::TwoLevelStepSolver::reportLines(std::vector<std::string>& lines) const {
  const AsyncRunStats& r = runStats_;
  char line[256];
  char modal[64] = "";
  if (r.zModalRegions > 0) std::snprintf(modal, sizeof(modal), ", %d region(s) from their modes", r.zModalRegions);
  std::snprintf(line, sizeof(line),
                "async set-up %.3f s (Z %.3f s over %lld right-hand sides on %d threads%s, H^LL* %.3f s); |S| %d, "
                "|I| %d, |L| %d DOFs",
                r.setupSeconds, r.setupZSeconds, r.zColumns, r.zThreads, modal, r.setupSchurSeconds, r.fastDofs,
                r.interfaceDofs, r.largeDofs);
  lines.emplace_back(line);
  lines.push_back(steadyStepLine(r));
  if (r.laggedSteps > 0) {
    std::snprintf(line, sizeof(line),
                  "async lagged Schur: %lld steps, %lld iterations, largest relative residual %.2e; %lld rebuilds "
                  "refreshed without Z",
                  r.laggedSteps, r.schurIterations, r.largestSchurResidual, r.laggedRefreshes);
    lines.emplace_back(line);
  }
  if (r.quickSteps > 0 || r.quickEnds > 0) {
    std::snprintf(line, sizeof(line),
                  "async quick set-up: %lld steps on the whole system's factor, %lld iterations (largest relative "
                  "residual %.2e); %lld partition(s) then built Z and H^LL*",
                  r.quickSteps, r.quickIterations, r.largestQuickResidual, r.quickEnds);
    lines.emplace_back(line);
  }
  appendContactLines(r, options_.contact.iterations, lines);
}

}  // namespace asyncfem
