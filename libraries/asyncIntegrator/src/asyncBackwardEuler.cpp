// SPDX-License-Identifier: BSD-3-Clause
// Asynchronous implicit backward Euler. Equation numbers (A1)-(A15) refer to
// docs/asynchronous-integrator.md, section "Method". The parts live in src/detail/:
// coupling (coefficients), fastRegion (A^S, Z, forward substitution), schurSolver
// (H^{LL*}), naiveSolver (the reference), interfaceElements (stable coupling).
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/asyncIntegrator/detail/vertexRotations.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/integrator/stepFormula.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "detail/fastRegion.hpp"
#include "detail/interfaceElements.hpp"
#include "detail/multirateSupport.hpp"
#include "detail/naiveSolver.hpp"
#include "detail/parallelTasks.hpp"
#include "detail/schurSolver.hpp"
#include "detail/sparseBlocks.hpp"
#include "detail/substepContact.hpp"
#include "detail/wholeSystemFactor.hpp"

namespace asyncfem {

using detail::FastRegion;
using detail::substepTime;
using SparseMatrix = Eigen::SparseMatrix<double>;

struct AsyncBackwardEuler::Impl {
  bool linear = true;
  bool factorsCurrent = false;     // linear forces: blocks and factors built for this timestep and partition
  bool settingUp = false;          // the build under way is a set-up (for AsyncRunStats)
  SparseMatrix stiffness;          // full 3n x 3n tangent K(u_0)
  bool perElementTangent = false;  // interface element tangents from the force model (else cached linear ones)
  Eigen::VectorXd internalForce;
  std::vector<FastRegion> regions;
  SubmatrixExtractor massLL, stiffLL;
  // M and K share one pattern (element matrices on the same mesh): K^{LL} is cut with
  // massLL's map and stiffLL stays empty. Checked once (-1: not yet).
  int sharedPattern = -1;
  // Linear forces: K is in stiffness (constant), so a new partition need not evaluate it again.
  bool linearStiffnessKnown = false;
  SparseMatrix Mll, Kll;     // M^{LL} (constant), K^{LL}; only when M and K have different patterns
  bool cutLL = false;        // L's blocks extracted once per partition; later only their values are updated
  SparseMatrix largeSystem;  // Â^L
  detail::SchurSolver schur;
  detail::VertexRotations rotations;  // since the last rebuild (laggedSchurRotation)
  detail::NaiveSolver naive;
  // This step refactored A^S but keeps Z and H^{LL*} from an earlier tangent (laggedSchur).
  bool schurLagging = false;
  // The lagged factor's rent-or-buy prices (flops, set at each full rebuild): one
  // refinement iteration, one rebuild, and the iterations paid since the last rebuild.
  double laggedIterationFlops = 0.0, laggedRebuildFlops = 0.0, laggedRent = 0.0;
  // Quick set-up (AsyncOptions::quickSetUp): L's system is solved on the whole system's
  // factor until the iterations' extra flops reach the priced cost of the rebuild (Eq. Q4).
  bool quick = false;
  // Whether the lagged factor was last built with Z (not refreshed): the next rebuild
  // the rule asks for may then be a refresh.
  bool lastRebuildFull = false;
  // The lagged solve converged with its tracker: recovery from the summed probes.
  bool recoverFromProbes = false;
  double quickExtraFlops = 0.0;
  // Linear forces with a symmetric K (checked once): f_int(u_0) = K u_0 and K v_0 are taken
  // row by row (row i = column i) on the DOFs that need them, and L's rows need only
  // K (u_0 + (beta + hL) v_0), as in single-rate backward Euler.
  bool symmetricStiffness = false;
  bool symmetryChecked = false;
  // Per-step buffers (full 3n, or |L|).
  Eigen::VectorXd stiffVelocity, massVelocity, stateForce, predicted, newU, newV, work;
  Eigen::VectorXd rhsL, rhsSchur, Y;
  std::vector<double> interfaceSum;  // regionDistribution: every region's interface rows, summed
  const Eigen::VectorXd* externalL = nullptr;
  // External forces at the distinct times of one large step (shared by regions whose
  // substeps fall on the same times), valid for one step.
  std::vector<double> forceTimes;
  std::vector<Eigen::VectorXd> forceValues;
  std::size_t forcesUsed = 0;
  // Each region's vertices with free DOFs (ascending), and a region's force at one
  // predicted substep: where the system has externalForceAt, substeps evaluate only them.
  std::vector<std::vector<int>> regionVertices;
  Eigen::VectorXd regionForce;
  // Implicit contact (DynamicSystem::externalForceJacobian): the contact iteration, and
  // whether a region's A^S holds contact blocks that Z and H^{LL*} were not built with.
  detail::SubstepContact contact;
  bool correctionsStale = false;
  // The first solve of an implicit contact step recovers end states only, for the
  // certificate (Eq. C6): each DOF's interval of displacements over the step's states, the
  // boxes' centres, the interface's share of each vertex's radius (squared) and the
  // vertices near an obstacle.
  bool certifying = false;
  Eigen::VectorXd lowest, highest, centred, runningPath;
  std::vector<double> reachSquares;
  std::vector<int> nearObstacles;
  // Each region's contact blocks in A^S when Z and H^{LL*} were last built (none at a
  // set-up): a step whose blocks are back to them (contact over, A^S refactored to what Z
  // was built from) has current corrections again, without a rebuild.
  struct BuiltBlocks {
    std::vector<std::array<int, 3>> positions;
    std::vector<Eigen::Matrix3d> blocks, stiffness;
  };
  std::vector<BuiltBlocks> schurBlocks;

  void noteSchurBlocks() {
    schurBlocks.resize(regions.size());
    for (std::size_t i = 0; i < regions.size(); ++i)
      schurBlocks[i] = {regions[i].contactPositions, regions[i].contactBlocks, regions[i].contactStiffness};
  }
  bool blocksAsBuilt() const {
    for (std::size_t i = 0; i < regions.size(); ++i) {
      const detail::FastRegion& rb = regions[i];
      if (i >= schurBlocks.size()) {
        if (rb.hasContactBlocks()) return false;
        continue;
      }
      const BuiltBlocks& built = schurBlocks[i];
      if (rb.contactPositions != built.positions || rb.contactBlocks != built.blocks ||
          rb.contactStiffness != built.stiffness)
        return false;
    }
    return true;
  }

  bool rowProducts() const { return linear && symmetricStiffness; }
  /// f_ext at time and state (u, v0), evaluated in this thread (the callback need not be
  /// thread-safe): once per distinct time at the start state u0, always anew at a predicted one.
  const Eigen::VectorXd& forceAt(const DynamicSystem& system, double time, const Eigen::VectorXd& u,
                                 const Eigen::VectorXd& u0, const Eigen::VectorXd& v0) {
    if (&u == &u0) {
      for (std::size_t k = 0; k < forcesUsed; ++k)
        if (forceTimes[k] == time) return forceValues[k];
    }
    if (forcesUsed == forceValues.size()) {
      forceValues.emplace_back();
      forceTimes.push_back(0.0);
    }
    Eigen::VectorXd& f = forceValues[forcesUsed];
    forceTimes[forcesUsed] = &u == &u0 ? time : std::nan("");  // predicted states are never shared
    ++forcesUsed;
    f.setZero(u0.size());
    system.externalForce(time, u, v0, f);
    return f;
  }
};

// A set-up kept for reuse by run-time regions (the most recently used first).
struct AsyncBackwardEuler::CachedSetUp {
  std::vector<std::pair<int, std::vector<int>>> key;  // (ratio, vertices) of every region, sorted
  RegionPartition partition;
  std::unique_ptr<Impl> impl;
  AsyncRunStats sizes;  // fastDofs, interfaceDofs, largeDofs
  double timestep = 0.0;
};

namespace {
/// Most doubles the quick set-up's deflation directions and their products may hold (64 MiB).
constexpr double kMaxDeflationEntries = 8.0 * 1024 * 1024;
/// What a flop of a supernodal factorization, or of a solve with many right-hand sides
/// (Z's columns in blocks), costs against one of a single solve (BLAS 3 against memory-
/// bound substitutions). Measured on this project's 2-core machine, one thread, corotational
/// beam and dinosaur (benchmarkAsync --study steady --corotational): a lagged iteration (the
/// forward substitutions with A^S, one-column kernel of sparseSolver, and the single-
/// precision kept factor) runs at about 7 GFlop/s, a rebuild (Z and the factor of H^{LL*})
/// at 9.6-10 GFlop/s: 0.7. (It was 0.4 while single solves went through CHOLMOD's BLAS
/// calls at 3.2-4.8 GFlop/s; priced at 0.4 since, rebuilds cost 1.7-2x their price.)
constexpr double kBlockedFlopWeight = 0.7;
/// The same weight for the quick set-up's rule (Eq. Q4), whose iterations solve with the
/// whole system's factor (millions of entries: CHOLMOD's solves with OpenBLAS's kernels, at
/// the 3.2-4.8 GFlop/s measured for it): 0.4.
constexpr double kQuickBlockedFlopWeight = 0.4;
/// The fixed cost of one solve call (wrapping, scatter and gather, CHOLMOD's workspace) in
/// flops of a solve, which dominates the small A^S solves of a forward substitution.
constexpr double kSolveCallFlops = 1e5;

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

/// A tolerance as a reader writes it (1e-10, not to_string's 0.000000).
std::string shortNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", value);
  return text;
}

std::vector<std::pair<int, std::vector<int>>> partitionKey(const RegionPartition& partition) {
  std::vector<std::pair<int, std::vector<int>>> key;
  for (int i = 0; i < partition.numRegions(); ++i) {
    std::vector<int> vertices = partition.region(i).vertices;
    std::sort(vertices.begin(), vertices.end());
    vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
    key.emplace_back(partition.ratio(i), std::move(vertices));
  }
  std::sort(key.begin(), key.end());
  return key;
}

}  // namespace

AsyncBackwardEuler::AsyncBackwardEuler(const TetMesh& mesh, DynamicSystem system, double largeTimestep,
                                       std::vector<AsyncRegion> regions, AsyncOptions options)
    : AsyncBackwardEuler(withMesh("async", mesh, std::move(system)), largeTimestep, std::move(regions), options) {}

AsyncBackwardEuler::AsyncBackwardEuler(DynamicSystem system, double largeTimestep, std::vector<AsyncRegion> regions,
                                       AsyncOptions options)
    : PartitionedIntegrator("async", std::move(system), largeTimestep, std::move(regions)),
      options_(options),
      impl_(freshImpl()) {
  if (options_.method == AsyncSolveMethod::nested) {
    throw ValidationError("async integrator: the method \"nested\" is NestedAsyncBackwardEuler's; build that instead");
  }
  if (options_.largeSystemSolver &&
      (options_.coupling != AsyncCoupling::stable || options_.method != AsyncSolveMethod::structured)) {
    throw ValidationError(
        "async integrator: an external solver of L's system (largeSystemSolver) needs the stable coupling and the "
        "structured method (it is given the symmetric H^{LL*})");
  }
  const AsyncOptions::RegionDistribution& distribution = options_.regionDistribution;
  if (static_cast<bool>(distribution.ownedRegions) != static_cast<bool>(distribution.sum)) {
    throw ValidationError("async integrator: regionDistribution needs both ownedRegions and sum");
  }
  if (distributed() &&
      (options_.coupling != AsyncCoupling::stable || options_.method != AsyncSolveMethod::structured)) {
    throw ValidationError(
        "async integrator: regions owned by one process (regionDistribution) need the stable coupling and the "
        "structured method");
  }
  if (!(options_.contactTolerance > 0.0 && options_.contactTolerance < 1.0) || options_.contactIterations < 1) {
    throw ValidationError("async integrator: contactTolerance must be in (0, 1) and contactIterations >= 1 (got " +
                          std::to_string(options_.contactTolerance) + ", " +
                          std::to_string(options_.contactIterations) + ")");
  }
  const Impl& d = *impl_;
  if (!system_.damped()) stats_.skipped.push_back("damping blocks (alpha = beta = 0)");
  if (d.linear)
    stats_.skipped.push_back("per-step refactorization (linear forces: blocks, Z and H^{LL*} factored once)");
  if (options_.method == AsyncSolveMethod::naive)
    stats_.skipped.push_back("Schur complement (naive full-system solve)");
  setUp(partition_);
}

AsyncBackwardEuler::~AsyncBackwardEuler() = default;

std::unique_ptr<AsyncBackwardEuler::Impl> AsyncBackwardEuler::freshImpl() const {
  auto impl = std::make_unique<Impl>();
  impl->linear = system_.forceModel->isLinear();
  impl->stiffness = system_.forceModel->createStiffnessMatrix();
  impl->stiffness.makeCompressed();
  return impl;
}

void AsyncBackwardEuler::setAdaptiveRegions(AdaptiveRegionOptions options) {
  if (options.contact && !system_.obstacleProximity) {
    throw ValidationError(
        "async integrator: adaptive regions: the contact policy needs obstacles (a \"contact\" section)");
  }
  policy_ = std::make_unique<AdaptiveRegionPolicy>(*system_.mesh, system_.freeDofs, std::move(options));
  stepsKept_ = 0;
  maybeRepartition();
}

// At a large-step boundary the state is synchronous: a new partition needs no transfer.
void AsyncBackwardEuler::maybeRepartition() {
  if (!policy_) return;
  std::vector<AsyncRegion> current;
  for (int i = 0; i < partition_.numRegions(); ++i) current.push_back(partition_.region(i));
  std::string reason;
  std::optional<std::vector<AsyncRegion>> next = policy_->decide(
      time(), timestep(), displacement_, velocity_, system_.obstacleProximity, current, stepsKept_, reason);
  if (next) repartition(std::move(*next), reason);
}

void AsyncBackwardEuler::repartition(std::vector<AsyncRegion> regions, const std::string& reason) {
  Stopwatch watch;
  RepartitionRecord record;
  record.time = time();
  record.step = runStats_.steps;
  record.reason = reason;
  const std::vector<int> before = partition_.vertexRegion();
  const std::vector<int> beforeRatio = [&] {
    std::vector<int> ratio(before.size(), 1);
    for (std::size_t v = 0; v < before.size(); ++v)
      if (before[v] >= 0) ratio[v] = partition_.ratio(before[v]);
    return ratio;
  }();
  RegionPartition next(*system_.mesh, system_.freeDofs, std::move(regions));
  auto key = partitionKey(next);
  auto hit = std::find_if(cache_.begin(), cache_.end(), [&](const CachedSetUp& c) { return c.key == key; });
  if (hit == cache_.end() && policy_) {
    // A cached partition that covers what the policy needs (a contact patch like one
    // seen before) serves as well as the new one, at no set-up.
    std::vector<AsyncRegion> proposal;
    for (int i = 0; i < next.numRegions(); ++i) proposal.push_back(next.region(i));
    hit = std::find_if(cache_.begin(), cache_.end(), [&](const CachedSetUp& c) {
      std::vector<AsyncRegion> cached;
      for (int i = 0; i < c.partition.numRegions(); ++i) cached.push_back(c.partition.region(i));
      return policy_->canServe(cached, proposal, time(), timestep(), displacement_, velocity_,
                               system_.obstacleProximity);
    });
  }
  CachedSetUp outgoing{partitionKey(partition_), std::move(partition_), std::move(impl_), runStats_, timestep()};
  const double setupBefore = runStats_.setupSeconds;
  if (hit != cache_.end()) {
    partition_ = std::move(hit->partition);
    impl_ = std::move(hit->impl);
    runStats_.fastDofs = hit->sizes.fastDofs;
    runStats_.interfaceDofs = hit->sizes.interfaceDofs;
    runStats_.largeDofs = hit->sizes.largeDofs;
    if (hit->timestep != timestep()) impl_->factorsCurrent = false;
    cache_.erase(hit);
    record.reused = true;
  } else {
    partition_ = RegionPartition(*system_.mesh, system_.freeDofs, {});  // placeholder until setUp
    impl_ = freshImpl();
    setUp(std::move(next));
  }
  const int keep = policy_ ? policy_->options().cacheSize : 0;
  if (keep > 0) cache_.insert(cache_.begin(), std::move(outgoing));
  // Least recently used out first, but the empty partition (single-rate at hL between
  // contacts) stays while it fits: it is the one every contact returns to.
  while (static_cast<int>(cache_.size()) > keep) {
    auto victim = cache_.end() - 1;
    if (victim->key.empty() && cache_.size() > 1) --victim;
    cache_.erase(victim);
  }
  stepsKept_ = 0;
  const std::vector<int>& after = partition_.vertexRegion();
  for (std::size_t v = 0; v < after.size(); ++v) {
    const int ratio = after[v] >= 0 ? partition_.ratio(after[v]) : 1;
    if (ratio != beforeRatio[v]) ++record.movedVertices;
    if (after[v] >= 0) ++record.fastVertices;
  }
  record.regions = partition_.numRegions();
  record.interfaceDofs = runStats_.interfaceDofs;
  record.seconds = record.reused ? watch.stop() : runStats_.setupSeconds - setupBefore;
  repartitions_.push_back(record);
}

void AsyncBackwardEuler::checkPartitionFits(const RegionPartition& partition) const {
  std::size_t partitioned = partition.largeDofs().size();
  for (int i = 0; i < partition.numRegions(); ++i) partitioned += partition.regionDofs(i).size();
  if (partition.vertexRegion().size() != static_cast<std::size_t>(system_.mesh->numVertices()) ||
      partitioned != system_.freeDofs.freeToFull().size()) {
    throw ValidationError("async integrator: setUp: the partition covers " +
                          std::to_string(partition.vertexRegion().size()) + " vertices and " +
                          std::to_string(partitioned) + " free DOFs, but the system has " +
                          std::to_string(system_.mesh->numVertices()) + " vertices and " +
                          std::to_string(system_.freeDofs.freeToFull().size()) +
                          " free DOFs: build it on system().mesh and system().freeDofs");
  }
}

void AsyncBackwardEuler::setUp(RegionPartition partition) {
  Impl& d = *impl_;
  Stopwatch watch;
  checkPartitionFits(partition);
  partition_ = std::move(partition);
  const SparseMatrix& mass = system_.mass;
  const std::vector<int>& large = partition_.largeDofs();
  if (d.sharedPattern < 0) d.sharedPattern = detail::samePattern(mass, d.stiffness) ? 1 : 0;
  d.massLL.rebuild(mass, large, large);  // in the storage of the previous partition's cut
  // Only implicit contact needs the DOF maps (1.7 ms of a 25 ms re-partition of the 10k dragon).
  if (implicitContact()) d.contact.setPartition(partition_, static_cast<int>(mass.rows()));
  if (d.sharedPattern != 1) d.stiffLL.rebuild(d.stiffness, large, large);
  d.cutLL = false;
  d.regions.clear();
  d.schurBlocks.clear();
  d.regions.reserve(static_cast<std::size_t>(partition_.numRegions()));
  runStats_.fastDofs = runStats_.interfaceDofs = 0;
  runStats_.largeDofs = static_cast<int>(large.size());
  d.regionVertices.assign(static_cast<std::size_t>(partition_.numRegions()), {});
  for (int i = 0; i < partition_.numRegions(); ++i) {
    const detail::RegionLayout layout{&partition_.regionDofs(i), &partition_.interfaceDofs(i), partition_.ratio(i)};
    d.regions.emplace_back(mass, d.stiffness, layout, options_.regionSolver, options_.denseRegionDofs);
    d.regions.back().trackReach = certifiesContactFree();
    std::vector<int>& vertices = d.regionVertices[static_cast<std::size_t>(i)];
    for (const int dof : partition_.regionDofs(i))  // ascending
      if (vertices.empty() || vertices.back() != dof / 3) vertices.push_back(dof / 3);
    runStats_.fastDofs += static_cast<int>(partition_.regionDofs(i).size());
    runStats_.interfaceDofs += static_cast<int>(partition_.interfaceDofs(i).size());
  }
  if (distributed()) assignRegionOwners();
  if (d.linear && !d.linearStiffnessKnown) {
    // K is constant: evaluated for the first partition, kept for the next ones (whose steps
    // evaluate f_int themselves).
    detail::evaluateForces(system_, true, false, displacement_, d.internalForce, d.stiffness, stats_);
    d.linearStiffnessKnown = true;
  }
  if (options_.coupling == AsyncCoupling::stable) {
    d.perElementTangent =
        detail::findInterfaceElements(*system_.mesh, partition_, system_, d.regions, d.linear ? &d.stiffness : nullptr);
  }
  d.schur.reset();
  if (options_.largeSystemSolver) {
    std::vector<std::vector<int>> interfaces;
    for (int i = 0; i < partition_.numRegions(); ++i) interfaces.push_back(partition_.interfaceDofs(i));
    d.schur.useExternalSolver(options_.largeSystemSolver, large, std::move(interfaces));
  }
  d.naive.reset();
  d.schurLagging = false;
  d.lastRebuildFull = false;  // no factor of H^{LL*} for this partition yet
  d.quick = options_.quickSetUp && options_.coupling == AsyncCoupling::stable &&
            options_.method == AsyncSolveMethod::structured;
  d.quickExtraFlops = 0.0;
  d.factorsCurrent = false;
  if (d.linear) {
    // K is constant: build and factor everything now, so the first step costs a steady one.
    d.settingUp = true;
    refactor();
    d.settingUp = false;
    d.factorsCurrent = true;
  }
  runStats_.setupSeconds += watch.stop();
}

bool AsyncBackwardEuler::implicitContact() const {
  return static_cast<bool>(system_.externalForceJacobian) && linearizesExternalForce();
}

bool AsyncBackwardEuler::certifiesContactFree() const {
  return implicitContact() && options_.certifyContactFree && system_.stateDependentOnlyInContact &&
         static_cast<bool>(system_.obstacleProximity);
}

bool AsyncBackwardEuler::linearizesExternalForce() const {
  return options_.coupling == AsyncCoupling::stable && options_.method == AsyncSolveMethod::structured &&
         !options_.largeSystemSolver && !distributed();
}

void AsyncBackwardEuler::setTimestep(double timestep) {
  Integrator::setTimestep(timestep);
  if (impl_) impl_->factorsCurrent = false;
}

// Every block from the current K (impl_->stiffness) and M, refactored, and the Schur
// complement. At set-up for linear forces, every large step otherwise.
void AsyncBackwardEuler::refactor() {
  Impl& d = *impl_;
  assembleBlocks();
  if (options_.method == AsyncSolveMethod::naive) {
    d.naive.factor(d.regions, d.largeSystem, partition_, system_.damped(), stats_);
    return;
  }
  // Structured: factor every A^S; Z = (H^{SS})^{-1} H^{SI}, the corrections C_i = H^{IS} Z
  // and H^{LL*} unless the lagged factor is kept this step.
  Stopwatch factor;
  runOwnedTasks(1, [&](int i) { d.regions[static_cast<std::size_t>(i)].factorize(stats_); });
  stats_.factorizationSeconds += factor.stop();
  priceSubstitutions();
  if (d.schurLagging) return;
  if (d.quick) {
    borrowWholeFactor();
    return;
  }
  fullSchurRebuild();
}

// Quick set-up: the whole single-rate system's factor, made once per hL (nonlinear forces:
// from the first tangent, then kept as a preconditioner) and shared by every partition.
void AsyncBackwardEuler::borrowWholeFactor() {
  Impl& d = *impl_;
  if (!whole_) whole_ = std::make_unique<detail::WholeSystemFactor>();
  if (!whole_->factoredFor(timestep())) {
    Stopwatch factor;
    whole_->factor(system_.mass, d.stiffness, system_.freeDofs.freeToFull(), timestep(), system_.rayleighMass,
                   system_.rayleighStiffness, stats_);
    const double seconds = factor.stop();
    stats_.factorizationSeconds += seconds;
    if (d.settingUp) runStats_.setupSchurSeconds += seconds;
  }
  if (!d.schur.borrowing()) d.schur.borrow(whole_.get(), partition_.largeDofs());
  if (!d.linear) d.schur.forgetDirections();  // a new tangent: H^{LL*} changed
}

// Blocks of M are constant: cut once. Blocks of K are updated in place (values only) and
// every combination reuses its pattern, so a refactorization step allocates nothing here.
void AsyncBackwardEuler::assembleBlocks() {
  Impl& d = *impl_;
  const double hL = timestep();
  const double alpha = system_.rayleighMass, beta = system_.rayleighStiffness;
  Stopwatch assembly;
  // A^L = M^{LL} + hL D^{LL} + hL^2 K^{LL} (Eq. A1 at hL).
  const stepFormula::MatrixWeights weights = stepFormula::backwardEuler::systemMatrix(hL, alpha, beta);
  if (d.sharedPattern == 1) {
    // One pass over L's entries of M and K (no M^{LL}, K^{LL} of their own).
    if (!d.cutLL) {
      d.massLL.extractCombinationInto(weights.mass, system_.mass, weights.stiffness, d.stiffness, d.largeSystem);
    } else {
      d.massLL.updateCombination(weights.mass, system_.mass, weights.stiffness, d.stiffness, d.largeSystem);
    }
  } else {
    if (!d.cutLL) d.Mll = d.massLL.extract(system_.mass);
    detail::updateBlock(d.stiffLL, d.stiffness, d.Kll, d.cutLL);
    detail::combineInto(weights.mass, d.Mll, weights.stiffness, d.Kll, d.largeSystem);
  }
  d.cutLL = true;
  for (FastRegion& rb : d.regions) rb.updateBlocks(d.stiffness, hL, alpha, beta, system_.damped(), options_.coupling);
  if (options_.coupling == AsyncCoupling::stable) subtractInterfaceStiffness();
  if (d.linear && !d.symmetryChecked) {
    const SparseMatrix transposed = d.stiffness.transpose();
    d.symmetricStiffness = (d.stiffness - transposed).norm() <= 1e-13 * d.stiffness.norm();
    d.symmetryChecked = true;
  }
  stats_.assemblySeconds += assembly.stop();
}

// Z, the Schur corrections and the H^{LL*} factor from the current blocks.
void AsyncBackwardEuler::fullSchurRebuild() {
  Impl& d = *impl_;
  const bool setUpBuild = d.settingUp;
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
  const double zSeconds = factor.stop();
  zColumnSeconds_ += zSeconds;
  stats_.factorizationSeconds += zSeconds;
  (setUpBuild ? runStats_.setupZSeconds : runStats_.rebuildZSeconds) += zSeconds;
  if (distributed()) shareCorrections();
  schurAsymmetry_ = 0.0;
  for (const FastRegion& rb : d.regions) {
    const double norm = rb.correction.norm();
    if (norm > 0.0) {
      schurAsymmetry_ = std::max(schurAsymmetry_, (rb.correction - rb.correction.transpose()).norm() / norm);
    }
  }
  factor.start();
  d.schur.factor(d.largeSystem, partition_, d.regions, options_.schur, options_.coupling, schurAsymmetry_, stats_);
  schurModeUsed_ = d.schur.modeUsed();
  d.contact.noteFactored();
  d.correctionsStale = false;
  d.noteSchurBlocks();
  const double schurSeconds = factor.stop();
  stats_.factorizationSeconds += schurSeconds;
  if (setUpBuild) runStats_.setupSchurSeconds += schurSeconds;
  d.schurLagging = false;
  d.lastRebuildFull = true;
  keepLaggedFactor();
}

// H^{LL*} refactored from the current Â^L with the corrections C_i kept (they are
// current): implicit contact's blocks of L changed, nothing else.
void AsyncBackwardEuler::refactorLargeSystem() {
  Impl& d = *impl_;
  Stopwatch factor;
  d.schur.factor(d.largeSystem, partition_, d.regions, options_.schur, options_.coupling, schurAsymmetry_, stats_);
  d.contact.noteFactored();
  stats_.factorizationSeconds += factor.stop();
  keepLaggedFactor();
}

// A refresh (laggedSchurRotation): the kept corrections C_i turned with the body since the
// factor was built (Eq. T2) and H^{LL*} refactored from the current A^L, without Z. The
// next rebuild the rule asks for is a full one.
void AsyncBackwardEuler::refreshLaggedFactor() {
  Impl& d = *impl_;
  Stopwatch factor;
  d.rotations.update(*system_.mesh, displacement_);
  for (int i = 0; i < partition_.numRegions(); ++i) {
    d.rotations.turnBlock(partition_.interfaceDofs(i), d.regions[static_cast<std::size_t>(i)].correction);
  }
  d.schur.factor(d.largeSystem, partition_, d.regions, options_.schur, options_.coupling, schurAsymmetry_, stats_);
  d.contact.noteFactored();
  stats_.factorizationSeconds += factor.stop();
  ++runStats_.laggedRefreshes;
  d.lastRebuildFull = false;
  keepLaggedFactor();
}

// After a factor of H^{LL*}: the rent-or-buy prices and, with laggedSchurRotation, the
// rotations measured from this state (where the factor's tangent was taken).
void AsyncBackwardEuler::keepLaggedFactor() {
  Impl& d = *impl_;
  priceLaggedFactor();
  if (!turnsLaggedFactor()) return;
  d.rotations.setReference(*system_.mesh, displacement_);
  const std::vector<int>& large = partition_.largeDofs();
  d.schur.setPreconditionerTransform(
      [&d, &large](Eigen::VectorXd& x, bool transpose) { d.rotations.rotate(large, x, transpose); });
}

bool AsyncBackwardEuler::turnsLaggedFactor() const {
  const Impl& d = *impl_;
  return options_.laggedSchur && options_.laggedSchurRotation && !d.linear && system_.mesh &&
         !options_.largeSystemSolver && options_.method == AsyncSolveMethod::structured;
}

// The flop prices of the lagged factor's rent-or-buy rule, with the same weights as the
// quick set-up's (Eq. Q4): an iteration is one forward substitution per region, one solve
// with the kept factor and one product with A^L; a rebuild is Z (|I_i| substitutions per
// region, in blocks) and the factorization of H^{LL*}.
void AsyncBackwardEuler::priceLaggedFactor() {
  Impl& d = *impl_;
  const SparseSolver* schur = d.schur.solver();
  d.laggedRent = 0.0;
  d.laggedIterationFlops = kSolveCallFlops + 2.0 * static_cast<double>(d.largeSystem.nonZeros()) +
                           (schur != nullptr ? schur->stats().solveFlopsPerRhs : 0.0);
  d.laggedRebuildFlops = schur != nullptr ? kBlockedFlopWeight * schur->stats().factorFlops : 0.0;
  for (std::size_t i = 0; i < d.regions.size(); ++i) {
    const FastRegion& rb = d.regions[i];
    const double substitution = rb.substitutionFlops;
    d.laggedIterationFlops += substitution + rb.ratio * kSolveCallFlops;
    d.laggedRebuildFlops +=
        kBlockedFlopWeight * substitution * static_cast<double>(partition_.interfaceDofs(static_cast<int>(i)).size());
  }
}

// Stable coupling: A^L becomes Â^L = A^L - sum_i (1 - theta_i) hL^2 K_{I_i}^{II} (Eq. A11),
// with K_{I_i} the tangent of region i's interface elements at u_0. The change lies on
// entries of interface-vertex pairs that share an element, so A^L's pattern holds them.
void AsyncBackwardEuler::subtractInterfaceStiffness() {
  Impl& d = *impl_;
  const std::vector<int>& large = partition_.largeDofs();
  for (int i = 0; i < partition_.numRegions(); ++i) {
    FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& pos = partition_.interfacePositions(i);
    rb.assembleInterfaceStiffness(*system_.forceModel, displacement_, d.perElementTangent);
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

void AsyncBackwardEuler::step() {
  maybeRepartition();
  Impl& d = *impl_;
  Stopwatch whole;
  const double rebuildBefore = runStats_.setupSeconds + runStats_.rebuildSeconds;
  // Step times come from the step index (t0 = k hL, t1 = (k + 1) hL).
  const double t0 = time();
  const double t1 = stepEndTime();
  evaluateStartOfStep();
  Stopwatch solve;
  gatherExternalForces(t0, t1);  // right-hand sides (A4), (A12)
  largeRightHandSide();
  regionRightHandSides();
  if (implicitContact()) {
    solveWithImplicitContact(t0, t1);
  } else if (options_.method == AsyncSolveMethod::naive) {
    d.naive.solve(d.regions, d.rhsL, d.Y);
  } else {
    solveStructured();
  }
  assembleNewState(t0, t1);
  stats_.solveSeconds += solve.stop();
  commitStep(d.newU, d.newV);
  countSolves();
  ++runStats_.steps;
  ++stepsKept_;
  runStats_.stepSeconds += whole.stop() - (runStats_.setupSeconds + runStats_.rebuildSeconds - rebuildBefore);
}

// Implicit contact (Eqs. C1-C6): Newton's method over the step (detail::SubstepContact),
// the contact blocks in Â^L and in the regions' A^S, until the residual is
// at most contactTolerance or contactIterations solves are spent.
void AsyncBackwardEuler::solveWithImplicitContact(double t0, double t1) {
  Impl& d = *impl_;
  const double hL = timestep();
  if (d.externalL == nullptr) throw Error("async integrator: implicit contact without an external force function");
  struct Restore {
    Impl& d;
    ~Restore() { d.contact.removeBlocks(d.largeSystem); }
  } restore{d};
  const detail::ContactStep step{&system_, &partition_,       &displacement_,        &velocity_, t0, t1,
                                 hL,       &d.regionVertices, certifiesContactFree()};
  if (d.contact.start(step, d.rhsL, *d.externalL, d.regions, d.largeSystem)) ++runStats_.contactScreenedSteps;
  refactorContactRegions();
  // Rent or buy, as for the lagged factor: once the iterations that stale corrections cost
  // have added up to a rebuild, rebuild (without the regions' contact blocks, below).
  if (d.correctionsStale && !d.schur.borrowing() && d.laggedRent >= d.laggedRebuildFlops) {
    Stopwatch rebuild;
    if (rebuildWithoutRegionBlocks()) ++runStats_.rebuilds;
    runStats_.rebuildSeconds += rebuild.stop();
  }
  // Eq. (C6): where nothing touches at the predicted states, the first solve recovers end
  // states only, and ends the step when no state of it can reach an obstacle.
  d.certifying = certifiesContactFree() && !d.contact.blocksInMatrix();
  for (const detail::FastRegion& rb : d.regions) d.certifying = d.certifying && !rb.hasContactBlocks();
  for (int iterations = 1;; ++iterations) {
    solveStructured();
    if (d.certifying) {
      d.certifying = false;
      if (contactFreeCertified()) {
        ++runStats_.contactIterations;
        ++runStats_.contactSteps;
        ++runStats_.contactFreeSteps;
        return;
      }
      for (int i = 0; i < partition_.numRegions(); ++i)
        if (!d.regions[static_cast<std::size_t>(i)].substituted) substituteRegion(i);
    }
    const double residual = d.contact.update(d.regions, d.Y, d.largeSystem, d.rhsL);
    refactorContactRegions();
    ++runStats_.contactIterations;
    if (!std::isfinite(residual)) {
      throw NumericalError("async integrator: the step to t = " + std::to_string(t1) +
                           " has a non-finite state or external force with implicit contact (vertex " +
                           std::to_string(d.contact.worstVertex()) + ")");
    }
    if (residual <= options_.contactTolerance) break;
    if (iterations < options_.contactIterations) continue;
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
bool AsyncBackwardEuler::rebuildWithoutRegionBlocks() {
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
  d.correctionsStale = !d.blocksAsBuilt();
  return true;
}

// The regions whose A^S the contact blocks just changed: refactored, Z and H^{LL*} stale
// unless every A^S is back to the blocks they were built with.
void AsyncBackwardEuler::refactorContactRegions() {
  Impl& d = *impl_;
  const std::vector<int>& changed = d.contact.changedRegions();
  if (changed.empty()) return;
  Stopwatch factor;
  for (int i : changed) d.regions[static_cast<std::size_t>(i)].factorize(stats_);
  runStats_.contactRegionFactorizations += static_cast<long long>(changed.size());
  stats_.factorizationSeconds += factor.stop();
  d.correctionsStale = !d.blocksAsBuilt();
}

// f_int(u_0) (and K(u_0) for nonlinear forces), then the refactorization a nonlinear step
// (or a linear one after setTimestep) needs.
void AsyncBackwardEuler::evaluateStartOfStep() {
  Impl& d = *impl_;
  if (!d.linear || !d.factorsCurrent || !d.symmetricStiffness) {
    detail::evaluateForces(system_, d.linear, d.factorsCurrent, displacement_, d.internalForce, d.stiffness, stats_);
  }
  if (d.linear && d.factorsCurrent) return;
  Stopwatch rebuild;
  const bool first = runStats_.rebuilds == 0 && runStats_.steps == 0;
  d.schurLagging = options_.laggedSchur && !d.linear && d.schur.factored() && !d.schur.refreshRequested() &&
                   d.laggedRent < d.laggedRebuildFlops && options_.method == AsyncSolveMethod::structured;
  // With the turned factor, every other rebuild the rule asks for is a refresh.
  // lastRebuildFull: this partition's H^{LL*} was factored with Z (so not borrowed, not quick).
  const bool refresh = !first && !d.schurLagging && d.lastRebuildFull && turnsLaggedFactor();
  if (refresh) d.schurLagging = true;  // refactor() then factors the regions' A^S only
  d.settingUp = first;
  refactor();
  if (refresh) refreshLaggedFactor();
  d.settingUp = false;
  d.factorsCurrent = true;
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
void AsyncBackwardEuler::gatherExternalForces(double t0, double t1) {
  Impl& d = *impl_;
  const Eigen::VectorXd& u0 = displacement_;
  const Eigen::VectorXd& v0 = velocity_;
  d.forcesUsed = 0;
  const bool hasExternal = static_cast<bool>(system_.externalForce);
  // Implicit contact starts its iteration from the predicted states (Eq. C3 at X = 0).
  const bool implicit = implicitContact();
  const bool predict = options_.substepStatePrediction || implicit;
  const bool constantInStep =
      hasExternal && !predict && system_.externalForceChanges && !system_.externalForceChanges(t0, t1);
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

// b^L = hL (f_ext - f_int(u_0) - D v_0) - hL^2 K v_0 (Eq. A1 at hL); for linear forces
// hL (f_ext - alpha M v_0 - K (u_0 + (beta + hL) v_0)). Stable coupling: plus Eq. (A12).
void AsyncBackwardEuler::largeRightHandSide() {
  Impl& d = *impl_;
  const Eigen::VectorXd& u0 = displacement_;
  const Eigen::VectorXd& v0 = velocity_;
  const double hL = timestep();
  const double alpha = system_.rayleighMass, beta = system_.rayleighStiffness;
  const bool massDamping = system_.damped() && alpha != 0.0;
  const stepFormula::RightHandSide recipe = stepFormula::backwardEuler::rightHandSide(hL, beta);
  if (massDamping) {
    d.massVelocity.resize(u0.size());
    d.massVelocity.noalias() = system_.mass * v0;
  }
  if (!d.rowProducts()) {
    d.stiffVelocity.resize(u0.size());
    d.stiffVelocity.noalias() = d.stiffness * v0;
    // The state-dependent part, once per large step: f_int(u_0) + D v_0.
    d.stateForce = d.internalForce;
    if (system_.damped()) {
      if (alpha != 0.0) d.stateForce += alpha * d.massVelocity;
      d.stateForce += beta * d.stiffVelocity;
    }
  } else {
    d.work = u0 + recipe.velocityStiffness * v0;
  }
  const std::vector<int>& large = partition_.largeDofs();
  d.rhsL.resize(static_cast<Eigen::Index>(large.size()));
  for (std::size_t k = 0; k < large.size(); ++k) {
    const int dof = large[k];
    const double external = d.externalL ? (*d.externalL)[dof] : 0.0;
    const double state = d.rowProducts() ? detail::columnDot(d.stiffness, dof, d.work) +
                                               (massDamping ? alpha * d.massVelocity[dof] : 0.0)
                                         : d.stateForce[dof] + hL * d.stiffVelocity[dof];
    d.rhsL[static_cast<Eigen::Index>(k)] = recipe.scale * (external - state);
  }
  if (options_.coupling == AsyncCoupling::stable) addInterfaceVelocityTerms();
}

// Stable coupling: b^L += (1 - theta) hL^2 (K^{IS} v^S_0 + K_I^{II} v^I_0) (Eq. A12).
void AsyncBackwardEuler::addInterfaceVelocityTerms() {
  Impl& d = *impl_;
  const Eigen::VectorXd& v0 = velocity_;
  for (int i = 0; i < partition_.numRegions(); ++i) {
    FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& pos = partition_.interfacePositions(i);
    if (pos.empty()) continue;
    detail::gatherInto(v0, partition_.regionDofs(i), rb.xSum);           // scratch: v^S_0
    detail::gatherInto(v0, partition_.interfaceDofs(i), rb.yInterface);  // scratch: v^I_0
    rb.interfaceRow.resize(static_cast<Eigen::Index>(pos.size()));
    rb.interfaceRow.noalias() = rb.Kis * rb.xSum;
    rb.interfaceRow.noalias() += rb.interfaceStiffness * rb.yInterface;
    for (std::size_t k = 0; k < pos.size(); ++k)
      d.rhsL[pos[k]] += rb.coupling.interfaceWeight * rb.interfaceRow[static_cast<Eigen::Index>(k)];
  }
}

// Every region's b^S (|S| x m, Eq. A4): b_r = hS (f_ext(t_r) - f_int(u_0) - (D + r hS K) v_0),
// from its DOFs only.
void AsyncBackwardEuler::regionRightHandSides() {
  Impl& d = *impl_;
  const Eigen::VectorXd& u0 = displacement_;
  const Eigen::VectorXd& v0 = velocity_;
  const double alpha = system_.rayleighMass, beta = system_.rayleighStiffness;
  const bool massDamping = system_.damped() && alpha != 0.0;
  detail::parallelTasks(partition_.numRegions(), detail::threadBudget(options_.threads), [&](int i) {
    FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& s = partition_.regionDofs(i);
    rb.rhs.resize(static_cast<Eigen::Index>(s.size()), rb.ratio);
    for (std::size_t k = 0; k < s.size(); ++k) {
      const int dof = s[k];
      const auto row = static_cast<Eigen::Index>(k);
      double state = 0.0, stiffVelocity = 0.0;  // (f_int(u_0) + D v_0)_dof and (K v_0)_dof
      if (d.rowProducts()) {
        stiffVelocity = detail::columnDot(d.stiffness, dof, v0);
        state = detail::columnDot(d.stiffness, dof, u0) + beta * stiffVelocity +
                (massDamping ? alpha * d.massVelocity[dof] : 0.0);
      } else {
        stiffVelocity = d.stiffVelocity[dof];
        state = d.stateForce[dof];
      }
      for (int r = 1; r <= rb.ratio; ++r) {
        const double tau = r * rb.smallStep;
        rb.rhs(row, r - 1) = rb.smallStep * (rb.external(row, r - 1) - state - tau * stiffVelocity);
      }
    }
  });
}

// Forward substitution y = (H^{SS})^{-1} b^S per region and its term of b^{L*} = b^L -
// H^{LS} y (Eq. A7); Y from H^{LL*} (Eq. A13); the regions' unknowns recovered from Y.
void AsyncBackwardEuler::solveStructured() {
  Impl& d = *impl_;
  const bool damped = system_.damped();
  const int threads = detail::threadBudget(options_.threads);
  runOwnedTasks(threads, [&](int i) {
    FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    rb.forwardSubstitute(rb.rhs, rb.y);
    if (rb.Mis.rows() > 0) rb.interfaceRowOf(rb.y, damped);
  });
  d.rhsSchur = d.rhsL;
  subtractOwnedInterfaceRows(d.rhsSchur);
  const auto apply = [this](const Eigen::VectorXd& y, Eigen::VectorXd& out) { applySchur(y, out); };
  d.recoverFromProbes = false;
  if (partition_.largeDofs().empty()) {
    d.Y.resize(0);
  } else if (d.schur.borrowing()) {
    solveOnWholeFactor();
  } else if (!d.schurLagging && d.contact.factorIsExact() && !d.correctionsStale) {
    d.schur.solve(d.rhsSchur, d.Y);
  } else {
    // At least laggedSchurIterations, and as many as one rebuild costs (rent or buy).
    if (turnsLaggedFactor()) d.rotations.update(*system_.mesh, displacement_);
    const double affordable = d.laggedRebuildFlops / std::max(d.laggedIterationFlops, 1.0);
    const int budget = std::max(options_.laggedSchurIterations, static_cast<int>(std::min(affordable, 1000.0)));
    const detail::SchurSolver::Tracker track = [this, threads](double coefficient, bool reset) {
      sumProbeSubstitutions(threads, coefficient, reset);
    };
    const detail::SchurSolver::Refinement result =
        d.schur.refine(d.rhsSchur, d.Y, apply, options_.coupling == AsyncCoupling::stable, budget,
                       options_.laggedSchurTolerance, track);
    d.recoverFromProbes = result.converged;
    runStats_.schurIterations += result.iterations;
    d.laggedRent += result.iterations * d.laggedIterationFlops;
    if (result.converged && !result.zeroRightHandSide) {
      ++runStats_.laggedSteps;
      runStats_.largestSchurResidual = std::max(runStats_.largestSchurResidual, result.residual);
    }
    if (!result.converged) {
      // The old factor no longer preconditions well enough: rebuild now (exact solve). With
      // Z and C_i current (only L's contact blocks changed), H^{LL*} alone.
      Stopwatch rebuild;
      if (!d.schurLagging && !d.correctionsStale) {
        refactorLargeSystem();
      } else {
        fullSchurRebuild();
      }
      runStats_.rebuildSeconds += rebuild.stop();
      d.schur.solve(d.rhsSchur, d.Y);
    }
  }
  runOwnedTasks(threads, [&](int i) { recoverRegion(i); });
  if (distributed()) shareRecoveries();
}

// Quick set-up (Eqs. Q1-Q3): deflated conjugate gradients on H^{LL*}, preconditioned by the
// Schur complement of the whole single-rate system on L. Exact with no region (H^{LL*} =
// A). The flops beyond one solve are what the missing factor costs; once they add up to the
// rebuild's price, or the iterations do not converge, Z and H^{LL*} are built (the rent-
// or-buy rule: about twice what knowing the partition's lifetime would have cost at most).
void AsyncBackwardEuler::solveOnWholeFactor() {
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
      d.schur.solveDeflated(d.rhsSchur, d.Y, apply, options_.quickSetUpIterations, options_.laggedSchurTolerance, keep);
  runStats_.quickIterations += result.iterations;
  if (result.converged) {
    ++runStats_.quickSteps;
    runStats_.largestQuickResidual = std::max(runStats_.largestQuickResidual, result.residual);
    const QuickCosts costs = quickCosts(d.regions, d.largeSystem, partition_, *whole_);
    const double deflation = 2.0 * static_cast<double>(d.schur.keptDirections()) * static_cast<double>(d.Y.size());
    d.quickExtraFlops += result.iterations * (costs.iteration + 2.0 * deflation) + 3.0 * deflation - costs.exactSolve;
    if (d.quickExtraFlops < costs.rebuild || !options_.quickSetUpRebuild) return;
  }
  Stopwatch rebuild;
  d.quick = false;
  fullSchurRebuild();
  ++runStats_.quickEnds;
  runStats_.rebuildSeconds += rebuild.stop();
  if (!result.converged) d.schur.solve(d.rhsSchur, d.Y);
}

// X_m and sum_r X_r from the stored Z_m and sum_r Z_r, or every X_r by a second forward
// substitution with b^S - H^{SL} Y (block r of H^{SL} Y = B_r Y_I).
void AsyncBackwardEuler::recoverRegion(int i) {
  Impl& d = *impl_;
  FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
  const std::vector<int>& pos = partition_.interfacePositions(i);
  if (pos.empty()) {
    std::swap(rb.x, rb.y);
    rb.substituted = true;
    return;
  }
  detail::gatherInto(d.Y, pos, rb.yInterface);
  if (d.recoverFromProbes) {
    // X = y - (H^{SS})^{-1} H^{SL} Y, the substitution of H^{SL} Y summed along the lagged
    // solve's iterations (forward substitution is linear): no substitution of its own.
    rb.x = rb.y;
    rb.x -= rb.probeSum;
    rb.substituted = true;
    return;
  }
  // Implicit contact evaluates the force at every substep: x must hold them all, unless
  // the step may be certified free of contact (Eq. C6) with the bounds of Z.
  const bool endStates = !implicitContact() || (d.certifying && rb.reach.size() == rb.y.rows());
  if (rb.useDenseZ && !observer_ && !d.schurLagging && !d.schur.borrowing() && endStates) {
    rb.xLast = rb.y.col(rb.ratio - 1);
    rb.xLast.noalias() -= rb.zLast * rb.yInterface;
    rb.xSum = rb.y.rowwise().sum();
    rb.xSum.noalias() -= rb.zSum * rb.yInterface;
    rb.substituted = false;
    return;
  }
  substituteRegion(i);
}

// Every X_r of region i by the forward substitution of b^S - H^{SL} Y (yInterface gathered).
void AsyncBackwardEuler::substituteRegion(int i) {
  Impl& d = *impl_;
  FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
  const bool damped = system_.damped();
  const detail::CouplingCoefficients& k = rb.coupling;
  rb.couplingProducts(damped);
  for (int r = 1; r <= rb.ratio; ++r) {
    rb.rhs.col(r - 1) -= k.bM[r - 1] * rb.massY + k.bK[r - 1] * rb.stiffY;
    if (damped) rb.rhs.col(r - 1) -= k.bD[r - 1] * rb.dampY;
  }
  rb.forwardSubstitute(rb.rhs, rb.x);
  rb.substituted = true;
}

// Eq. (C6). Per DOF, the interval of its displacement from u_0 over every state the
// iteration looks at: the predicted ones (r hS v_0, hL v_0), L's end state hL (v_0 + Y),
// and a region's substeps along the substitution of b^S alone (y, or x where it was
// substituted), hS (r v_0 + sum_{j<=r} y_j). Each vertex's states then lie within its
// box's half-diagonal, plus reach |Y_I|_2 for a region's (the rows' bounds in 2-norm),
// of the box's centre: no free vertex with its centre within the largest such radius of
// an obstacle (depth is 1-Lipschitz in the position) means no state touches, and the force
// at each is the predicted one (stateDependentOnlyInContact).
bool AsyncBackwardEuler::contactFreeCertified() {
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

// v^S_r = v^S_0 + X_r, u^S_m = u^S_0 + hS sum_r v^S_r; v^L = v^L_0 + Y, u^L = u^L_0 + hL v^L.
void AsyncBackwardEuler::assembleNewState(double t0, double t1) {
  Impl& d = *impl_;
  const Eigen::VectorXd& u0 = displacement_;
  const Eigen::VectorXd& v0 = velocity_;
  d.newU = u0;
  d.newV = v0;
  for (int i = 0; i < partition_.numRegions(); ++i) {
    FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& s = partition_.regionDofs(i);
    const int m = rb.ratio;
    if (rb.substituted) {
      rb.xLast = rb.x.col(m - 1);
      rb.xSum = rb.x.rowwise().sum();
    }
    for (std::size_t k = 0; k < s.size(); ++k) {
      const auto row = static_cast<Eigen::Index>(k);
      d.newV[s[k]] = v0[s[k]] + rb.xLast[row];
      d.newU[s[k]] = u0[s[k]] + rb.smallStep * (m * v0[s[k]] + rb.xSum[row]);
    }
    if (!observer_ || !rb.owned) continue;
    // Substep states, only for an installed observer (x then holds every substep).
    const Eigen::VectorXd vS0 = detail::gather(v0, s), uS0 = detail::gather(u0, s);
    Eigen::VectorXd running = Eigen::VectorXd::Zero(rb.x.rows());
    for (int r = 1; r <= m; ++r) {
      running += rb.x.col(r - 1);
      const Eigen::VectorXd uS = uS0 + rb.smallStep * (double(r) * vS0 + running);
      const Eigen::VectorXd vS = vS0 + rb.x.col(r - 1);
      observer_(i, r, substepTime(t0, t1, r, m, rb.smallStep), uS, vS);
    }
  }
  const std::vector<int>& large = partition_.largeDofs();
  const double hL = timestep();
  for (std::size_t k = 0; k < large.size(); ++k) {
    d.newV[large[k]] = v0[large[k]] + d.Y[static_cast<Eigen::Index>(k)];
    d.newU[large[k]] = u0[large[k]] + hL * d.newV[large[k]];
  }
}

// Solve counts and flops, totalled over the solvers (Z columns included).
void AsyncBackwardEuler::countSolves() {
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

// The lagged solve's tracker (SchurSolver::Tracker): every region's probeSum follows
// (H^{SS})^{-1} H^{SL} Y as Y moves, from the substitutions applySchur made anyway.
void AsyncBackwardEuler::sumProbeSubstitutions(int threads, double coefficient, bool reset) {
  Impl& d = *impl_;
  runOwnedTasks(threads, [&](int i) {
    FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    if (partition_.interfacePositions(i).empty()) return;
    if (reset) {
      rb.probeSum = rb.probeSolution;
    } else {
      rb.probeSum += coefficient * rb.probeSolution;
    }
  });
}

// out = H^{LL*} y for the current blocks: Â^L y minus, per region, the interface rows of
// H^{LS} (H^{SS})^{-1} H^{SL} y (one forward substitution per region).
void AsyncBackwardEuler::applySchur(const Eigen::VectorXd& y, Eigen::VectorXd& out) {
  Impl& d = *impl_;
  const bool damped = system_.damped();
  out.resize(y.size());
  out.noalias() = d.largeSystem * y;
  runOwnedTasks(detail::threadBudget(options_.threads), [&](int i) {
    FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& pos = partition_.interfacePositions(i);
    if (pos.empty()) return;
    detail::gatherInto(y, pos, rb.yInterface);
    const detail::CouplingCoefficients& k = rb.coupling;
    rb.couplingProducts(damped);
    rb.probe.resize(rb.massY.size(), rb.ratio);
    for (int r = 1; r <= rb.ratio; ++r) {
      rb.probe.col(r - 1) = k.bM[r - 1] * rb.massY + k.bK[r - 1] * rb.stiffY;
      if (damped) rb.probe.col(r - 1) += k.bD[r - 1] * rb.dampY;
    }
    rb.forwardSubstitute(rb.probe, rb.probeSolution);
    rb.interfaceRowOf(rb.probeSolution, damped);
  });
  subtractOwnedInterfaceRows(out);
}

// Regions owned by one process (AsyncOptions::regionDistribution). Every process steps the
// same state and cuts every region's blocks (Â^L and the right-hand sides need them); only
// a region's owner factors A^S, computes Z and C_i, substitutes and recovers. The sums
// over processes below hand the others what they need, at the same points on every
// process, so all of them hold the same H^{LL*}, Y and new state and take the same
// decisions (lagged factor, rent or buy). A failure in a process's region work is held
// until the next sum, which carries it to every process, so all stop at the same point.

// task(i) for every region this process owns (all of them when not distributed).
void AsyncBackwardEuler::runOwnedTasks(int threads, const std::function<void(int)>& task) {
  Impl& d = *impl_;
  if (!distributed()) {
    detail::parallelTasks(partition_.numRegions(), threads, task);
    return;
  }
  std::vector<std::exception_ptr> failures(d.regions.size());
  detail::parallelTasks(partition_.numRegions(), threads, [&](int i) {
    if (!d.regions[static_cast<std::size_t>(i)].owned) return;
    try {
      task(i);
    } catch (...) {
      failures[static_cast<std::size_t>(i)] = std::current_exception();
    }
  });
  for (std::size_t i = 0; i < failures.size(); ++i) {
    if (failures[i] && !heldFailure_) {
      heldFailure_ = failures[i];
      heldFailureRegion_ = static_cast<int>(i);
    }
  }
}

// Inside a catch block: holds the exception in flight (region: -1 when not known).
void AsyncBackwardEuler::holdFailure(int region) {
  if (heldFailure_) return;
  heldFailure_ = std::current_exception();
  heldFailureRegion_ = region;
}

// values summed over the processes, with two more entries that count the processes
// holding a failure and add up their failing regions (+1): every process then throws,
// the failing one its own exception, the others an Error naming the region.
void AsyncBackwardEuler::sumOverProcesses(std::vector<double>& values) {
  values.push_back(heldFailure_ ? 1.0 : 0.0);
  values.push_back(heldFailure_ ? heldFailureRegion_ + 1.0 : 0.0);
  options_.regionDistribution.sum(values.data(), values.size());
  const double failed = values[values.size() - 2], region = values.back() - 1.0;
  values.resize(values.size() - 2);
  if (failed == 0.0) return;
  if (heldFailure_) {
    const std::exception_ptr failure = heldFailure_;
    heldFailure_ = nullptr;
    std::rethrow_exception(failure);
  }
  std::string which = "a fast region";
  if (failed == 1.0 && region >= 0.0 && region < partition_.numRegions()) {
    const int i = static_cast<int>(region);
    which = "fast region " + std::to_string(i) + " (" + partition_.region(i).name + ")";
  }
  throw Error("async integrator: " + which +
              ", computed by another process, failed in this step (that process reports why); every process stops "
              "here");
}

void AsyncBackwardEuler::assignRegionOwners() {
  Impl& d = *impl_;
  const int numRegions = partition_.numRegions();
  std::vector<std::vector<int>> regionDofs, interfaceDofs;
  for (int i = 0; i < numRegions; ++i) {
    regionDofs.push_back(partition_.regionDofs(i));
    interfaceDofs.push_back(partition_.interfaceDofs(i));
  }
  // A bad answer on one process must still reach the sum, or the others would wait there.
  std::vector<char> owned;
  std::vector<double> owners(static_cast<std::size_t>(numRegions), 0.0);
  try {
    owned = options_.regionDistribution.ownedRegions(regionDofs, interfaceDofs);
    if (owned.size() != static_cast<std::size_t>(numRegions)) {
      throw ValidationError("async integrator: regionDistribution.ownedRegions answered for " +
                            std::to_string(owned.size()) + " regions, the partition has " + std::to_string(numRegions));
    }
    std::copy(owned.begin(), owned.end(), owners.begin());
  } catch (...) {
    holdFailure(-1);
  }
  sumOverProcesses(owners);
  for (int i = 0; i < numRegions; ++i) {
    const double count = owners[static_cast<std::size_t>(i)];
    if (count != 1.0) {
      throw ValidationError("async integrator: region " + std::to_string(i) + " (" + partition_.region(i).name +
                            ") has " + std::to_string(static_cast<int>(count)) +
                            " owners over the processes (regionDistribution.ownedRegions must give it exactly one)");
    }
    d.regions[static_cast<std::size_t>(i)].owned = owned[static_cast<std::size_t>(i)] != 0;
  }
}

// Each region's substitution flops, from its owner's factor (the rent-or-buy prices).
void AsyncBackwardEuler::priceSubstitutions() {
  Impl& d = *impl_;
  std::vector<double> flops(d.regions.size(), 0.0);
  for (std::size_t i = 0; i < d.regions.size(); ++i) {
    const FastRegion& rb = d.regions[i];
    if (rb.owned) flops[i] = rb.ratio * (rb.solver->stats().solveFlopsPerRhs + 2.0 * double(rb.G.nonZeros()));
  }
  if (distributed()) sumOverProcesses(flops);
  for (std::size_t i = 0; i < d.regions.size(); ++i) d.regions[i].substitutionFlops = flops[i];
}

// Every C_i from its owner (the others hold zeros).
void AsyncBackwardEuler::shareCorrections() {
  Impl& d = *impl_;
  std::vector<double> all;
  for (const FastRegion& rb : d.regions)
    all.insert(all.end(), rb.correction.data(), rb.correction.data() + rb.correction.size());
  sumOverProcesses(all);
  std::size_t at = 0;
  for (FastRegion& rb : d.regions) {
    std::copy_n(all.data() + at, rb.correction.size(), rb.correction.data());
    at += static_cast<std::size_t>(rb.correction.size());
  }
}

// target -= the interface rows of every region's last substitution (interfaceRow) at its
// interface positions; distributed, from the owners' rows summed over the processes (only
// the sum of |I_i| values travels, not vectors of L's size).
void AsyncBackwardEuler::subtractOwnedInterfaceRows(Eigen::VectorXd& target) {
  Impl& d = *impl_;
  const int numRegions = partition_.numRegions();
  if (!distributed()) {
    for (int i = 0; i < numRegions; ++i) {
      const FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
      const std::vector<int>& pos = partition_.interfacePositions(i);
      for (std::size_t k = 0; k < pos.size(); ++k) target[pos[k]] -= rb.interfaceRow[static_cast<Eigen::Index>(k)];
    }
    return;
  }
  // Every region's rows, concatenated in region order (sizes |I_i| known to every process):
  // the owner fills its segment, the sum hands it to all, and the subtraction below runs in
  // the order of the one-process path.
  d.interfaceSum.clear();
  for (int i = 0; i < numRegions; ++i) {
    const FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    const std::size_t size = partition_.interfacePositions(i).size();
    if (rb.owned) {
      d.interfaceSum.insert(d.interfaceSum.end(), rb.interfaceRow.data(), rb.interfaceRow.data() + size);
    } else {
      d.interfaceSum.insert(d.interfaceSum.end(), size, 0.0);
    }
  }
  sumOverProcesses(d.interfaceSum);
  std::size_t at = 0;
  for (int i = 0; i < numRegions; ++i) {
    const std::vector<int>& pos = partition_.interfacePositions(i);
    for (std::size_t k = 0; k < pos.size(); ++k) target[pos[k]] -= d.interfaceSum[at + k];
    at += pos.size();
  }
}

// X_m and sum_r X_r of every region from its owner, for the new state.
void AsyncBackwardEuler::shareRecoveries() {
  Impl& d = *impl_;
  std::vector<double> all;
  for (FastRegion& rb : d.regions) {
    const auto sizeS = static_cast<Eigen::Index>(rb.systemMatrix.rows());
    if (!rb.owned) {
      rb.xLast.setZero(sizeS);
      rb.xSum.setZero(sizeS);
    } else if (rb.substituted) {
      rb.xLast = rb.x.col(rb.ratio - 1);
      rb.xSum = rb.x.rowwise().sum();
    }
    all.insert(all.end(), rb.xLast.data(), rb.xLast.data() + sizeS);
    all.insert(all.end(), rb.xSum.data(), rb.xSum.data() + sizeS);
  }
  sumOverProcesses(all);
  std::size_t at = 0;
  for (FastRegion& rb : d.regions) {
    const auto sizeS = static_cast<std::size_t>(rb.systemMatrix.rows());
    std::copy_n(all.data() + at, sizeS, rb.xLast.data());
    std::copy_n(all.data() + at + sizeS, sizeS, rb.xSum.data());
    at += 2 * sizeS;
    if (!rb.owned) rb.substituted = false;
  }
}

double AsyncBackwardEuler::solveFloorSeconds(int repeats) {
  Impl& d = *impl_;
  if (!d.factorsCurrent)
    throw Error("solveFloorSeconds: take one step first (the factors are built at the first step)");
  std::vector<double> samples;
  for (int k = 0; k < std::max(1, repeats); ++k) {
    Stopwatch watch;
    if (options_.method == AsyncSolveMethod::naive) {
      d.naive.solveRandom();
    } else {
      for (FastRegion& rb : d.regions) {
        if (!rb.owned) continue;
        const bool dense = rb.useDenseZ || rb.Msi.cols() == 0;
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

long long AsyncBackwardEuler::factorNonZeros() const {
  const Impl& d = *impl_;
  if (options_.method == AsyncSolveMethod::naive) return d.naive.solver().stats().factorNonZeros;
  long long total = 0;
  for (const FastRegion& rb : d.regions) total += rb.solver->stats().factorNonZeros;
  return total + (d.schur.solver() ? d.schur.solver()->stats().factorNonZeros : 0);
}

namespace {

// The summary's lines on implicit contact (none without contact steps).
void appendContactLines(const AsyncRunStats& r, int contactIterations, std::vector<std::string>& lines) {
  if (r.contactSteps == 0) return;
  char line[256];
  std::snprintf(line, sizeof(line),
                "async implicit contact: %lld solves over %lld steps (%.2f per step); %lld steps stopped at %d "
                "iterations unconverged (largest relative residual %.2e); A^S refactored %lld times for its "
                "contact blocks",
                r.contactIterations, r.contactSteps,
                static_cast<double>(r.contactIterations) / static_cast<double>(r.contactSteps),
                r.unconvergedContactSteps, contactIterations, r.largestContactResidual, r.contactRegionFactorizations);
  lines.emplace_back(line);
  if (r.contactFreeSteps == 0 && r.contactScreenedSteps == 0) return;
  std::snprintf(line, sizeof(line),
                "async implicit contact: %lld of those steps certified free of contact after one solve (end states "
                "only, Eq. C6); %lld started with no substep state to visit (predicted states clear, Eq. C7)",
                r.contactFreeSteps, r.contactScreenedSteps);
  lines.emplace_back(line);
}

}  // namespace

RunReport AsyncBackwardEuler::report() const {
  const AsyncRunStats& r = runStats_;
  char line[256];
  RunReport report;
  report.factorNonZeros = factorNonZeros();
  report.mayGainEnergy = options_.coupling == AsyncCoupling::paper;
  const auto addCaveat = [&report](const std::string& caveat) {
    if (!report.resumeCaveat.empty()) report.resumeCaveat += "; ";
    report.resumeCaveat += caveat;
  };
  if (options_.laggedSchur && !impl_->linear && options_.method == AsyncSolveMethod::structured) {
    addCaveat(
        "laggedSchur: the H^{LL*} factor kept as preconditioner is not in the checkpoint, so the resumed run "
        "refactors at its first step; its frames match an uninterrupted run to about the Schur tolerance (" +
        shortNumber(options_.laggedSchurTolerance) + "), not bit for bit");
  }
  if (options_.quickSetUp && options_.coupling == AsyncCoupling::stable &&
      options_.method == AsyncSolveMethod::structured) {
    addCaveat(
        "quickSetUp: whether the partition still solved on the whole system's factor is not in the checkpoint, "
        "so the resumed run starts on it again; its frames match an uninterrupted run to about the Schur "
        "tolerance (" +
        shortNumber(options_.laggedSchurTolerance) + "), not bit for bit");
  }
  if (implicitContact()) {
    addCaveat(
        "implicit contact: the contact blocks kept in the regions' A^S (and the factors built with them) are not in "
        "the checkpoint, so the resumed run's contact iterations start from other matrices; its frames match an "
        "uninterrupted run to about the contact tolerance (" +
        shortNumber(options_.contactTolerance) + "), not bit for bit");
  }
  if (policy_) {
    addCaveat(
        "adaptive regions: the partition in use and how long it has been kept are not in the checkpoint, so the "
        "resumed run chooses its regions afresh from the resumed state and its frames can differ from an "
        "uninterrupted run's (by as much as two partitions' trajectories differ)");
  }
  std::vector<std::string>& lines = report.lines;
  if (!regionNote_.empty()) lines.push_back("regions " + regionNote_);
  std::snprintf(line, sizeof(line),
                "async set-up %.3f s (Z %.3f s over %lld right-hand sides on %d threads, H^LL* %.3f s); |S| %d, "
                "|I| %d, |L| %d DOFs",
                r.setupSeconds, r.setupZSeconds, r.zColumns, r.zThreads, r.setupSchurSeconds, r.fastDofs,
                r.interfaceDofs, r.largeDofs);
  lines.emplace_back(line);
  std::snprintf(line, sizeof(line), "async steady large step %.3f ms over %lld steps; rebuilds %lld (%.3f s)",
                1000.0 * r.meanStepSeconds(), r.steps, r.rebuilds, r.rebuildSeconds);
  lines.emplace_back(line);
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
  appendContactLines(r, options_.contactIterations, lines);
  if (policy_) appendRepartitionLines(repartitions_, lines);
  return report;
}

}  // namespace asyncfem
