// SPDX-License-Identifier: BSD-3-Clause
// The two-level step solvers: set-up, the blocks and their factors, and one large step.
// Equation numbers (A1)-(A15) refer to docs/asynchronous-integrator.md, section "Method".
// The other parts, one concept per file: structuredStep.cpp (right-hand sides, Schur solve,
// recovery), laggedSchur.cpp, quickSetUp.cpp, implicitContact.cpp, regionDistribution.cpp.
// The numerical pieces live in src/detail/: coupling (coefficients), fastRegion (A^S, Z,
// forward substitution), schurSolver (H^{LL*}), naiveSolver (the reference),
// interfaceElements (stable coupling).
#include "twoLevelStepSolver.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <asyncfem/asyncIntegrator/detail/vertexRotations.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/integrator/stepFormula.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <cmath>
#include <cstdio>
#include <string>

#include "detail/contactIteration.hpp"
#include "detail/fastRegion.hpp"
#include "detail/flopPrices.hpp"
#include "detail/interfaceElements.hpp"
#include "detail/multirateSupport.hpp"
#include "detail/naiveSolver.hpp"
#include "detail/parallelTasks.hpp"
#include "detail/schurSolver.hpp"
#include "detail/sparseBlocks.hpp"
#include "detail/wholeSystemFactor.hpp"

namespace asyncfem {

using detail::FastRegion;
using detail::StepEnd;
using detail::substepTime;
using detail::TwoLevelStepSolver;
using SparseMatrix = Eigen::SparseMatrix<double>;

TwoLevelStepSolver::TwoLevelStepSolver(AsyncStepSolver kind, const StepContext& context)
    : StepSolver(context), kind_(kind), impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.model.linear = system_.forceModel->isLinear();
  d.stiffness = system_.forceModel->createStiffnessMatrix();
  d.stiffness.makeCompressed();
}

TwoLevelStepSolver::~TwoLevelStepSolver() = default;

// Cuts every block on the partition's pattern and finds the interface elements; linear
// forces also build and factor everything now, so the first step costs a steady one.
void TwoLevelStepSolver::setUp() {
  Impl& d = *impl_;
  const SparseMatrix& mass = system_.mass;
  const std::vector<int>& large = partition_.largeDofs();
  if (d.build.sharedPattern < 0) d.build.sharedPattern = detail::samePattern(mass, d.stiffness) ? 1 : 0;
  d.massLL.rebuild(mass, large, large);  // in the storage of the previous partition's cut
  // Only implicit contact needs the DOF maps (1.7 ms of a 25 ms re-partition of the 10k dragon).
  if (implicitContact()) d.contact.setPartition(partition_, static_cast<int>(mass.rows()));
  if (d.build.sharedPattern != 1) d.stiffLL.rebuild(d.stiffness, large, large);
  d.build.cutLL = false;
  d.regions.clear();
  d.schurBlocks.clear();
  d.regions.reserve(static_cast<std::size_t>(partition_.numRegions()));
  runStats_.fastDofs = runStats_.interfaceDofs = 0;
  runStats_.largeDofs = static_cast<int>(large.size());
  d.regionVertices.assign(static_cast<std::size_t>(partition_.numRegions()), {});
  for (int i = 0; i < partition_.numRegions(); ++i) {
    const detail::RegionLayout layout{&partition_.regionDofs(i), &partition_.interfaceDofs(i), partition_.ratio(i)};
    d.regions.emplace_back(mass, d.stiffness, layout, options_.regionSolver, options_.denseRegionDofs);
    d.regions.back().dense.trackReach = certifiesContactFree();
    std::vector<int>& vertices = d.regionVertices[static_cast<std::size_t>(i)];
    for (const int dof : partition_.regionDofs(i))  // ascending
      if (vertices.empty() || vertices.back() != dof / 3) vertices.push_back(dof / 3);
    runStats_.fastDofs += static_cast<int>(partition_.regionDofs(i).size());
    runStats_.interfaceDofs += static_cast<int>(partition_.interfaceDofs(i).size());
  }
  if (system_.externalForceOfRank) d.ranked.setPartition(partition_, system_.freeDofs, d.regionVertices);
  if (distributed()) assignRegionOwners();
  if (d.model.linear && !d.build.stiffnessKnown) {
    // K is constant: evaluated for the first partition, kept for the next ones (whose steps
    // evaluate f_int themselves).
    detail::evaluateForces(system_, true, false, displacement_, d.internalForce, d.stiffness, stats_);
    d.build.stiffnessKnown = true;
  }
  if (options_.coupling == AsyncCoupling::stable) {
    d.model.perElementTangent = detail::findInterfaceElements(*system_.mesh, partition_, system_, d.regions,
                                                              d.model.linear ? &d.stiffness : nullptr);
  }
  d.schur.reset();
  if (options_.processes.largeSystemSolver) {
    std::vector<std::vector<int>> interfaces;
    for (int i = 0; i < partition_.numRegions(); ++i) interfaces.push_back(partition_.interfaceDofs(i));
    d.schur.useExternalSolver(options_.processes.largeSystemSolver, large, std::move(interfaces));
  }
  d.naive.reset();
  d.lagged.lagging = false;
  d.lagged.lastRebuildFull = false;  // no factor of H^{LL*} for this partition yet
  d.quickPath.active = options_.keptFactors.quickSetUp && options_.coupling == AsyncCoupling::stable &&
                       options_.method == AsyncSolveMethod::structured;
  d.quickPath.extraFlops = 0.0;
  d.build.factorsCurrent = false;
  if (d.model.linear) {
    // K is constant: build and factor everything now, so the first step costs a steady one.
    d.build.settingUp = true;
    refactor();
    d.build.settingUp = false;
    d.build.factorsCurrent = true;
  }
}

// Every block from the current K (impl_->stiffness) and M, refactored, and the Schur
// complement. At set-up for linear forces, every large step otherwise.
void TwoLevelStepSolver::refactor() {
  Impl& d = *impl_;
  assembleBlocks();
  if (kind_ == AsyncStepSolver::naiveLU) {
    d.naive.factor(d.regions, d.largeSystem, partition_, system_.damped(), stats_);
    return;
  }
  // Structured: factor every A^S; Z = (H^{SS})^{-1} H^{SI}, the corrections C_i = H^{IS} Z
  // and H^{LL*} unless the lagged factor is kept this step.
  Stopwatch factor;
  runOwnedTasks(1, [&](int i) { d.regions[static_cast<std::size_t>(i)].factorize(stats_); });
  stats_.factorizationSeconds += factor.stop();
  priceSubstitutions();
  if (d.lagged.lagging) return;
  if (d.quickPath.active) {
    borrowWholeFactor();
    return;
  }
  fullSchurRebuild();
}

// Blocks of M are constant: cut once. Blocks of K are updated in place (values only) and
// every combination reuses its pattern, so a refactorization step allocates nothing here.
void TwoLevelStepSolver::assembleBlocks() {
  Impl& d = *impl_;
  const double hL = timestep();
  const double alpha = system_.rayleighMass, beta = system_.rayleighStiffness;
  Stopwatch assembly;
  // A^L = M^{LL} + hL D^{LL} + hL^2 K^{LL} (Eq. A1 at hL).
  const stepFormula::MatrixWeights weights = stepFormula::backwardEuler::systemMatrix(hL, alpha, beta);
  if (d.build.sharedPattern == 1) {
    // One pass over L's entries of M and K (no M^{LL}, K^{LL} of their own).
    if (!d.build.cutLL) {
      d.massLL.extractCombinationInto(weights.mass, system_.mass, weights.stiffness, d.stiffness, d.largeSystem);
    } else {
      d.massLL.updateCombination(weights.mass, system_.mass, weights.stiffness, d.stiffness, d.largeSystem);
    }
  } else {
    if (!d.build.cutLL) d.Mll = d.massLL.extract(system_.mass);
    detail::updateBlock(d.stiffLL, d.stiffness, d.Kll, d.build.cutLL);
    detail::combineInto(weights.mass, d.Mll, weights.stiffness, d.Kll, d.largeSystem);
  }
  d.build.cutLL = true;
  for (FastRegion& rb : d.regions) rb.updateBlocks(d.stiffness, hL, alpha, beta, system_.damped(), options_.coupling);
  if (options_.coupling == AsyncCoupling::stable) subtractInterfaceStiffness();
  if (d.model.linear && !d.model.symmetryChecked) {
    const SparseMatrix transposed = d.stiffness.transpose();
    d.model.symmetricStiffness = (d.stiffness - transposed).norm() <= 1e-13 * d.stiffness.norm();
    d.model.symmetryChecked = true;
  }
  stats_.assemblySeconds += assembly.stop();
}

// Z, the Schur corrections and the H^{LL*} factor from the current blocks.
void TwoLevelStepSolver::fullSchurRebuild() {
  Impl& d = *impl_;
  const bool setUpBuild = d.build.settingUp;
  Stopwatch factor;
  detail::CorrectionRun run;
  try {
    run = detail::computeCorrections(d.regions, options_, system_.damped());
  } catch (...) {
    if (!distributed()) throw;
    holdFailure(-1);
  }
  stats_.factorizations += run.helperFactorizations;
  runStats_.zThreads = run.threads;
  runStats_.zColumns = run.columns;
  runStats_.zModalRegions = run.modalRegions;
  const double zSeconds = factor.stop();
  schurReport_.zColumnSeconds += zSeconds;
  stats_.factorizationSeconds += zSeconds;
  (setUpBuild ? runStats_.setupZSeconds : runStats_.rebuildZSeconds) += zSeconds;
  if (distributed()) shareCorrections();
  schurReport_.asymmetry = 0.0;
  for (const FastRegion& rb : d.regions) {
    const double norm = rb.correction.norm();
    if (norm > 0.0) {
      schurReport_.asymmetry =
          std::max(schurReport_.asymmetry, (rb.correction - rb.correction.transpose()).norm() / norm);
    }
  }
  factor.start();
  d.schur.factor(d.largeSystem, partition_, d.regions, options_.schur, options_.coupling, schurReport_.asymmetry,
                 stats_);
  schurReport_.modeUsed = d.schur.modeUsed();
  d.contact.noteFactored();
  d.contactStep.correctionsStale = false;
  d.noteSchurBlocks();
  const double schurSeconds = factor.stop();
  stats_.factorizationSeconds += schurSeconds;
  if (setUpBuild) runStats_.setupSchurSeconds += schurSeconds;
  d.lagged.lagging = false;
  d.lagged.lastRebuildFull = true;
  keepLaggedFactor();
}

// H^{LL*} refactored from the current Â^L with the corrections C_i kept (they are
// current): implicit contact's blocks of L changed, nothing else.
void TwoLevelStepSolver::refactorLargeSystem() {
  Impl& d = *impl_;
  Stopwatch factor;
  d.schur.factor(d.largeSystem, partition_, d.regions, options_.schur, options_.coupling, schurReport_.asymmetry,
                 stats_);
  d.contact.noteFactored();
  stats_.factorizationSeconds += factor.stop();
  keepLaggedFactor();
}

// Stable coupling: A^L becomes Â^L = A^L - sum_i (1 - theta_i) hL^2 K_{I_i}^{II} (Eq. A11),
// with K_{I_i} the tangent of region i's interface elements at u_0. The change lies on
// entries of interface-vertex pairs that share an element, so A^L's pattern holds them.
void TwoLevelStepSolver::subtractInterfaceStiffness() {
  Impl& d = *impl_;
  const std::vector<int>& large = partition_.largeDofs();
  for (int i = 0; i < partition_.numRegions(); ++i) {
    FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& pos = partition_.interfacePositions(i);
    rb.assembleInterfaceStiffness(*system_.forceModel, displacement_, d.model.perElementTangent);
    const auto q = static_cast<Eigen::Index>(pos.size());
    for (Eigen::Index b = 0; b < q; ++b) {
      for (Eigen::Index a = 0; a < q; ++a) {
        if (rb.interfaceStiffness(a, b) == 0.0) continue;
        const int row = pos[static_cast<std::size_t>(a)], column = pos[static_cast<std::size_t>(b)];
        double* entry = detail::findEntry(d.largeSystem, row, column);
        if (entry == nullptr) {
          throw Error("async integrator: interface DOFs " + std::to_string(large[static_cast<std::size_t>(row)]) +
                      " and " + std::to_string(large[static_cast<std::size_t>(column)]) +
                      " share an element but not an entry of A^L (the mass and stiffness patterns differ)");
        }
        *entry -= rb.coupling.interfaceWeight * rb.interfaceStiffness(a, b);
      }
    }
  }
}

// One large step: f_int and the factors at the start state, the right-hand sides (A4),
// (A12), the coupled solve and the end state.
StepEnd TwoLevelStepSolver::step(double t0, double t1) {
  Impl& d = *impl_;
  evaluateStartOfStep();
  Stopwatch solve;
  gatherExternalForces(t0, t1);  // right-hand sides (A4), (A12)
  largeRightHandSide();
  regionRightHandSides();
  if (implicitContact()) {
    solveWithImplicitContact(t0, t1);
  } else if (kind_ == AsyncStepSolver::naiveLU) {
    d.naive.solve(d.regions, d.rhsL, d.Y);
  } else {
    solveStructured();
  }
  assembleNewState(t0, t1);
  stats_.solveSeconds += solve.stop();
  countSolves();
  return {d.newU, d.newV};
}

// f_int(u_0) (and K(u_0) for nonlinear forces), then the refactorization a nonlinear step
// (or a linear one after setTimestep) needs.
void TwoLevelStepSolver::evaluateStartOfStep() {
  Impl& d = *impl_;
  if (!d.model.linear || !d.build.factorsCurrent || !d.model.symmetricStiffness) {
    detail::evaluateForces(system_, d.model.linear, d.build.factorsCurrent, displacement_, d.internalForce, d.stiffness,
                           stats_);
  }
  if (d.model.linear && d.build.factorsCurrent) return;
  Stopwatch rebuild;
  const bool first = runStats_.rebuilds == 0 && runStats_.steps == 0;
  d.lagged.lagging = options_.keptFactors.laggedSchur && !d.model.linear && d.schur.factored() &&
                     !d.schur.refreshRequested() && d.lagged.rent < d.lagged.rebuildFlops &&
                     options_.method == AsyncSolveMethod::structured;
  // With the turned factor, every other rebuild the rule asks for is a refresh.
  // lastRebuildFull: this partition's H^{LL*} was factored with Z (so not borrowed, not quick).
  const bool refresh = !first && !d.lagged.lagging && d.lagged.lastRebuildFull && turnsLaggedFactor();
  if (refresh) d.lagged.lagging = true;  // refactor() then factors the regions' A^S only
  d.build.settingUp = first;
  refactor();
  if (refresh) refreshLaggedFactor();
  d.build.settingUp = false;
  d.build.factorsCurrent = true;
  const double seconds = rebuild.stop();
  if (first) {
    runStats_.setupSeconds += seconds;
  } else {
    runStats_.rebuildSeconds += seconds;
    ++runStats_.rebuilds;
  }
}

// f_ext on every region at its substeps (rb.external, |S| x m) and on L at t1. At the start
// state, a force that the system says is constant in (t0, t1] (no load window opens or
// closes there) is evaluated once, at t1, for every substep.
void TwoLevelStepSolver::gatherExternalForces(double t0, double t1) {
  Impl& d = *impl_;
  const Eigen::VectorXd& u0 = displacement_;
  const Eigen::VectorXd& v0 = velocity_;
  d.forcesUsed = 0;
  const bool hasExternal = static_cast<bool>(system_.externalForce);
  // Implicit contact starts its iteration from the predicted states (Eq. C3 at X = 0).
  const bool implicit = implicitContact();
  const bool predict = options_.contact.substepStatePrediction || implicit;
  const bool constantInStep =
      hasExternal && !predict && system_.externalForceChanges && !system_.externalForceChanges(t0, t1);
  if (hasExternal && predict && system_.externalForceOfRank) {
    gatherRankedForces(t0, t1, implicit);
    return;
  }
  for (int i = 0; i < partition_.numRegions(); ++i) {
    FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& s = partition_.regionDofs(i);
    const auto sizeS = static_cast<Eigen::Index>(s.size());
    rb.external.resize(sizeS, rb.ratio);
    if (!hasExternal) {
      rb.external.setZero();
      continue;
    }
    // At the predicted substep states only the region's own entries are read: with
    // externalForceAt only its vertices are evaluated (the same values).
    const bool atVertices = predict && static_cast<bool>(system_.externalForceAt);
    const std::vector<int>& vertices = d.regionVertices[static_cast<std::size_t>(i)];
    if (atVertices) {
      d.regionForce.resize(u0.size());
      d.predicted = u0;
    }
    for (int r = 1; r <= rb.ratio; ++r) {
      const double time = constantInStep ? t1 : substepTime(t0, t1, r, rb.ratio, rb.smallStep);
      const Eigen::VectorXd* f = nullptr;
      if (atVertices) {
        // Only the listed vertices' state is read (DynamicSystem::externalForceAt).
        for (const int dof : s) d.predicted[dof] = u0[dof] + (r * rb.smallStep) * v0[dof];
        for (const int v : vertices) d.regionForce.segment<3>(3 * static_cast<Eigen::Index>(v)).setZero();
        system_.externalForceAt(time, d.predicted, v0, vertices, d.regionForce);
        f = &d.regionForce;
      } else if (predict) {
        d.predicted = u0 + (r * rb.smallStep) * v0;
        f = &d.forceAt(system_, time, d.predicted, u0, v0);
      } else {
        f = &d.forceAt(system_, time, u0, u0, v0);
      }
      for (Eigen::Index k = 0; k < sizeS; ++k) rb.external(k, r - 1) = (*f)[s[static_cast<std::size_t>(k)]];
    }
  }
  if (hasExternal && implicit) {
    d.predicted = u0 + timestep() * v0;
    d.externalL = &d.forceAt(system_, t1, d.predicted, u0, v0);
  } else {
    d.externalL = hasExternal ? &d.forceAt(system_, t1, u0, u0, v0) : nullptr;
  }
}

// gatherExternalForces where the system splits its force by rank (surface contact): at
// region i's substep r the whole body at its predicted state u_0 + r hS_i v_0, each term at
// the states of its rank (detail::RankedForces); L's own terms at the predicted end state
// (implicit contact) or at u_0.
void TwoLevelStepSolver::gatherRankedForces(double t0, double t1, bool implicit) {
  Impl& d = *impl_;
  const Eigen::VectorXd& u0 = displacement_;
  const Eigen::VectorXd& v0 = velocity_;
  d.ranked.clear();
  for (int i = 0; i < partition_.numRegions(); ++i) {
    const FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    for (int r = 1; r <= rb.ratio; ++r) {
      d.predicted = u0 + (r * rb.smallStep) * v0;
      d.ranked.addRegion(system_, i, r, substepTime(t0, t1, r, rb.ratio, rb.smallStep), d.predicted, v0);
    }
  }
  if (implicit) d.predicted = u0 + timestep() * v0;
  d.ranked.addLarge(system_, t1, implicit ? d.predicted : u0, v0);
  for (int i = 0; i < partition_.numRegions(); ++i)
    d.regions[static_cast<std::size_t>(i)].external = d.ranked.region[static_cast<std::size_t>(i)];
  d.rankedL.setZero(u0.size());
  const std::vector<int>& large = partition_.largeDofs();
  for (std::size_t k = 0; k < large.size(); ++k) d.rankedL[large[k]] = d.ranked.large[static_cast<Eigen::Index>(k)];
  d.externalL = &d.rankedL;
}

// Solve counts and flops, totalled over the solvers (Z columns included).
void TwoLevelStepSolver::countSolves() {
  const Impl& d = *impl_;
  stats_.solvedRightHandSides = 0;
  stats_.solveFlops = 0.0;
  detail::addSolveCounts(d.naive.solver(), stats_);
  if (d.schur.solver()) detail::addSolveCounts(*d.schur.solver(), stats_);
  for (const FastRegion& rb : d.regions) {
    detail::addSolveCounts(*rb.solver, stats_);
    for (const auto& helper : rb.helperSolvers) detail::addSolveCounts(*helper, stats_);
  }
}

double TwoLevelStepSolver::solveFloorSeconds(int repeats) {
  Impl& d = *impl_;
  if (!d.build.factorsCurrent)
    throw Error("solveFloorSeconds: take one step first (the factors are built at the first step)");
  std::vector<double> samples;
  for (int k = 0; k < std::max(1, repeats); ++k) {
    Stopwatch watch;
    if (kind_ == AsyncStepSolver::naiveLU) {
      d.naive.solveRandom();
    } else {
      for (FastRegion& rb : d.regions) {
        if (!rb.owned) continue;
        const bool dense = rb.dense.recovery || rb.Msi.cols() == 0;
        const int solves = dense ? rb.ratio : 2 * rb.ratio;
        const Eigen::VectorXd rhs = Eigen::VectorXd::Random(rb.systemMatrix.rows());
        for (int r = 0; r < solves; ++r) rb.solver->solve(rhs);
      }
      if (d.largeSystem.rows() > 0) {
        Eigen::VectorXd solution;
        d.schur.solve(Eigen::VectorXd::Random(d.largeSystem.rows()), solution);
      }
    }
    samples.push_back(watch.stop());
  }
  std::sort(samples.begin(), samples.end());
  return samples[samples.size() / 2];
}

long long TwoLevelStepSolver::factorNonZeros() const {
  const Impl& d = *impl_;
  if (kind_ == AsyncStepSolver::naiveLU) return d.naive.solver().stats().factorNonZeros;
  long long total = 0;
  for (const FastRegion& rb : d.regions) total += rb.solver->stats().factorNonZeros;
  return total + (d.schur.solver() ? d.schur.solver()->stats().factorNonZeros : 0);
}

}  // namespace asyncfem
