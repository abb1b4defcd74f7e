// SPDX-License-Identifier: BSD-3-Clause
// Implicit contact: Newton over the step with the contact blocks in A^L and the regions'
// A^S, and the contact-free certificate (docs/asynchronous-integrator.md, Eqs. C1-C7).
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <cmath>
#include <string>

#include "detail/multirateSupport.hpp"
#include "detail/parallelTasks.hpp"
#include "twoLevelStepSolver.hpp"

namespace asyncfem {

using detail::TwoLevelStepSolver;

using detail::FastRegion;
using detail::substepTime;

bool TwoLevelStepSolver::certifiesContactFree() const {
  return implicitContact() && options_.contact.certifyContactFree && system_.stateDependentOnlyInContact &&
         static_cast<bool>(system_.obstacleProximity);
}

// Implicit contact (Eqs. C1-C6): Newton's method over the step (detail::ContactIteration),
// the contact blocks in Â^L and in the regions' A^S, until the residual is
// at most contactTolerance or contactIterations solves are spent.
void TwoLevelStepSolver::solveWithImplicitContact(double t0, double t1) {
  Impl& d = *impl_;
  const double hL = timestep();
  if (d.externalL == nullptr) throw Error("async integrator: implicit contact without an external force function");
  struct Restore {
    Impl& d;
    ~Restore() { d.contact.removeBlocks(d.largeSystem); }
  } restore{d};
  detail::ContactStep step{&system_, &partition_,       &displacement_,        &velocity_, t0, t1,
                           hL,       &d.regionVertices, certifiesContactFree()};
  if (system_.externalForceOfRank) step.ranked = &d.ranked;
  if (d.contact.start(step, d.rhsL, *d.externalL, d.regions, d.largeSystem)) ++runStats_.contactScreenedSteps;
  refactorContactRegions();
  // Rent or buy, as for the lagged factor: once the iterations that stale corrections cost
  // have added up to a rebuild, rebuild (without the regions' contact blocks, below).
  if (d.contactStep.correctionsStale && !d.schur.borrowing() && d.lagged.rent >= d.lagged.rebuildFlops) {
    Stopwatch rebuild;
    if (rebuildWithoutRegionBlocks()) ++runStats_.rebuilds;
    runStats_.rebuildSeconds += rebuild.stop();
  }
  // Eq. (C6): where nothing touches at the predicted states, the first solve recovers end
  // states only, and ends the step when no state of it can reach an obstacle.
  d.contactStep.certifying = certifiesContactFree() && !d.contact.blocksInMatrix();
  for (const detail::FastRegion& rb : d.regions)
    d.contactStep.certifying = d.contactStep.certifying && !rb.hasContactBlocks();
  for (int iterations = 1;; ++iterations) {
    solveStructured();
    if (d.contactStep.certifying) {
      d.contactStep.certifying = false;
      if (contactFreeCertified()) {
        ++runStats_.contactIterations;
        ++runStats_.contactSteps;
        ++runStats_.contactFreeSteps;
        return;
      }
      for (int i = 0; i < partition_.numRegions(); ++i)
        if (!d.regions[static_cast<std::size_t>(i)].substituted) substituteRegion(i);
    }
    const bool hadPairBlocks = !d.contact.droppedPairBlocks();
    const double residual = d.contact.update(d.regions, d.Y, d.largeSystem, d.rhsL);
    if (hadPairBlocks && d.contact.droppedPairBlocks()) ++runStats_.contactPairBlocksDropped;
    refactorContactRegions();
    ++runStats_.contactIterations;
    if (!std::isfinite(residual)) {
      throw NumericalError("async integrator: the step to t = " + std::to_string(t1) +
                           " has a non-finite state or external force with implicit contact (vertex " +
                           std::to_string(d.contact.worstVertex()) + ")");
    }
    if (residual <= options_.contact.tolerance) break;
    if (iterations < options_.contact.iterations) continue;
    if (residual > 1.0) {
      const int vertex = d.contact.worstVertex();
      const int region = vertex >= 0 ? partition_.vertexRegion()[static_cast<std::size_t>(vertex)] : -1;
      throw NumericalError(
          "async integrator: implicit contact did not converge in the step to t = " + std::to_string(t1) +
          ": relative residual " + std::to_string(residual) + " after " + std::to_string(iterations) +
          " iterations, largest at vertex " + std::to_string(vertex) +
          (region >= 0 ? " of fast region " + std::to_string(region) + " (" + partition_.region(region).name +
                             "): its contact springs may be too stiff for hS = hL / " +
                             std::to_string(partition_.ratio(region)) + " (raise the ratio, or use backward-euler)"
                       : " of L"));
    }
    ++runStats_.unconvergedContactSteps;
    runStats_.largestContactResidual = std::max(runStats_.largestContactResidual, residual);
    break;
  }
  ++runStats_.contactSteps;
}

// Rent or buy for Z and H^{LL*} at the start of a contact step (the rent has reached a
// rebuild's price). A region's contact blocks change at every iteration and are gone when
// its contact ends (a strike, a bounce, a sliding or rolling patch), so a build with them
// is stale at once: Z and H^{LL*} are rebuilt with the regions' A^S as they are without
// contact, exact for every step after the contact (refactorContactRegions) and
// preconditioning the lagged solves during it, and left as they are when they were built
// that way already. Returns whether it rebuilt. A contact that rests keeps its lagged
// solves (each within the refinement's budget; one that does not converge in it forces a
// rebuild with the blocks, solveStructured). Measured (offlineSimulator, one thread, the
// same contact iterations; before, every rebuild took the step's blocks): antenna strike
// at ratio 60, 120 frames 11.1 -> 6.6 ms per frame (7 rebuilds -> 0), ball at k = 2e4 3.33 -> 3.10 s
// (1 -> 0), frictionless drop on the sphere at k = 2e4 19.1 -> 17.1 s (8 -> 0). Rebuilding
// with the step's blocks where they were the last step's (a contact at rest) once the rent
// reached twice the price cost 9% (ball) and 4% (drop) more in paired runs: not kept.
bool TwoLevelStepSolver::rebuildWithoutRegionBlocks() {
  Impl& d = *impl_;
  bool builtWithBlocks = false;
  for (const Impl::BuiltBlocks& built : d.schurBlocks) builtWithBlocks = builtWithBlocks || !built.positions.empty();
  if (!builtWithBlocks && !d.schurBlocks.empty()) return false;
  std::vector<Impl::BuiltBlocks> kept(d.regions.size());
  for (std::size_t i = 0; i < d.regions.size(); ++i) {
    detail::FastRegion& rb = d.regions[i];
    kept[i] = {rb.contactPositions, rb.contactBlocks, rb.contactStiffness};
    if (rb.setContactBlocks({}, {}, {})) rb.factorize(stats_);
  }
  fullSchurRebuild();
  for (std::size_t i = 0; i < d.regions.size(); ++i) {
    detail::FastRegion& rb = d.regions[i];
    if (rb.setContactBlocks(kept[i].positions, kept[i].blocks, kept[i].stiffness)) rb.factorize(stats_);
  }
  d.contactStep.correctionsStale = !d.blocksAsBuilt();
  return true;
}

// The regions whose A^S the contact blocks just changed: refactored, Z and H^{LL*} stale
// unless every A^S is back to the blocks they were built with.
void TwoLevelStepSolver::refactorContactRegions() {
  Impl& d = *impl_;
  const std::vector<int>& changed = d.contact.changedRegions();
  if (changed.empty()) return;
  Stopwatch factor;
  for (int i : changed) d.regions[static_cast<std::size_t>(i)].factorize(stats_);
  runStats_.contactRegionFactorizations += static_cast<long long>(changed.size());
  stats_.factorizationSeconds += factor.stop();
  d.contactStep.correctionsStale = !d.blocksAsBuilt();
}

// Eq. (C6). Per DOF, the interval of its displacement from u_0 over every state the
// iteration looks at: the predicted ones (r hS v_0, hL v_0), L's end state hL (v_0 + Y),
// and a region's substeps along the substitution of b^S alone (y, or x where it was
// substituted), hS (r v_0 + sum_{j<=r} y_j). Each vertex's states then lie within its
// box's half-diagonal, plus reach |Y_I|_2 for a region's (the rows' bounds in 2-norm),
// of the box's centre: no free vertex with its centre within the largest such radius of
// an obstacle (depth is 1-Lipschitz in the position) means no state touches, and the force
// at each is the predicted one (stateDependentOnlyInContact).
bool TwoLevelStepSolver::contactFreeCertified() {
  Impl& d = *impl_;
  const Eigen::VectorXd& v0 = velocity_;
  const double hL = timestep();
  d.lowest = hL * v0;
  d.highest = d.lowest;
  const auto include = [&d](Eigen::Index dof, double value) {
    d.lowest[dof] = std::min(d.lowest[dof], value);
    d.highest[dof] = std::max(d.highest[dof], value);
  };
  const std::vector<int>& large = partition_.largeDofs();
  for (std::size_t k = 0; k < large.size(); ++k)
    include(large[k], hL * (v0[large[k]] + d.Y[static_cast<Eigen::Index>(k)]));
  d.reachSquares.assign(static_cast<std::size_t>(v0.size() / 3), 0.0);
  for (int i = 0; i < partition_.numRegions(); ++i) {
    const FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& s = partition_.regionDofs(i);
    const Eigen::MatrixXd& path = rb.substituted ? rb.x : rb.y;
    // The predicted states lie on the segment from hS v_0 to hL v_0 (the latter included).
    for (const int dof : s) include(dof, rb.smallStep * v0[dof]);
    d.runningPath.setZero(path.rows());
    for (int r = 1; r <= rb.ratio; ++r) {
      d.runningPath += path.col(r - 1);
      for (std::size_t k = 0; k < s.size(); ++k)
        include(s[k], rb.smallStep * ((r * v0[s[k]]) + d.runningPath[static_cast<Eigen::Index>(k)]));
    }
    const double interface = rb.substituted ? 0.0 : rb.yInterface.norm();
    for (std::size_t k = 0; k < s.size() && interface > 0.0; ++k) {
      const double bound = rb.reach[static_cast<Eigen::Index>(k)] * interface;
      d.reachSquares[static_cast<std::size_t>(s[k] / 3)] += bound * bound;
    }
  }
  double radius = 0.0;
  d.centred = displacement_ + (0.5 * (d.lowest + d.highest));
  for (std::size_t v = 0; v < d.reachSquares.size(); ++v) {
    const auto dof = static_cast<Eigen::Index>(3 * v);
    const double halfDiagonal = 0.5 * (d.highest.segment<3>(dof) - d.lowest.segment<3>(dof)).norm();
    radius = std::max(radius, halfDiagonal + std::sqrt(d.reachSquares[v]));
  }
  return !detail::freeVertexNearObstacle(system_, d.centred, radius, d.nearObstacles);
}

}  // namespace asyncfem
