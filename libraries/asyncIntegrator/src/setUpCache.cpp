// SPDX-License-Identifier: BSD-3-Clause
// Run-time regions: the policy asked at each large-step boundary, re-partitions, and the
// cache of set-ups they reuse (docs/asynchronous-integrator.md, "Run-time regions").
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <cmath>
#include <string>

#include "detail/multirateSupport.hpp"
#include "stepSolvers.hpp"

namespace asyncfem {

namespace {

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

void AsyncBackwardEuler::setRunTimeRegions(RunTimeRegionOptions options) {
  if (options.contact && !system_.obstacleProximity) {
    throw ValidationError(
        "async integrator: run-time regions: the contact policy needs obstacles (a \"contact\" section)");
  }
  if (options.nest) requireHierarchyComposes(options_, "run-time regions that nest");
  if (options.loads && !system_.externalForce) {
    throw ValidationError("async integrator: run-time regions: the loads policy needs loads (an external force)");
  }
  policy_ = std::make_unique<RunTimeRegionPolicy>(*system_.mesh, system_.freeDofs, std::move(options));
  policy_->setExternalForce(system_.externalForce, system_.externalForceChanges);
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
  // As setUp() will solve it (regions touching at one ratio merged), so the cache key is
  // the partition's set-up.
  next = mergeTouchingAtOneRatio(*system_.mesh, system_.freeDofs, std::move(next));
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
  CachedSetUp outgoing{partitionKey(partition_), std::move(partition_), std::move(solver_), runStats_, timestep()};
  const double setupBefore = runStats_.setupSeconds;
  if (hit != cache_.end()) {
    partition_ = std::move(hit->partition);
    solver_ = std::move(hit->solver);
    runStats_.fastDofs = hit->sizes.fastDofs;
    runStats_.interfaceDofs = hit->sizes.interfaceDofs;
    runStats_.largeDofs = hit->sizes.largeDofs;
    if (hit->timestep != timestep()) solver_->invalidateFactors();
    cache_.erase(hit);
    record.reused = true;
  } else {
    partition_ = RegionPartition(*system_.mesh, system_.freeDofs, {});  // placeholder until setUp
    setUp(std::move(next));  // solver_ is empty: a fresh solver for the new partition
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

}  // namespace asyncfem
