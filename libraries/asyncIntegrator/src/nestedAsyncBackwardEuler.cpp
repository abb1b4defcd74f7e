// SPDX-License-Identifier: BSD-3-Clause
// Equation numbers refer to docs/asynchronous-integrator.md, "Nested and touching regions".
#include <algorithm>
#include <asyncfem/asyncIntegrator/nestedAsyncBackwardEuler.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <cstdio>
#include <map>
#include <numeric>
#include <set>
#include <string>

#include "detail/hierarchySystem.hpp"

namespace asyncfem {

namespace {

/// Largest large step in time units (least common multiple of the counts) accepted.
constexpr long long kMaxUnits = 1LL << 20;

const TetMesh& meshOf(const DynamicSystem& system) {
  if (!system.mesh) {
    throw ValidationError(
        "async integrator (nested regions): the dynamic system has no mesh (set DynamicSystem::mesh, as "
        "Problem::dynamicSystem() does)");
  }
  return *system.mesh;
}

std::string describeRegion(const std::vector<AsyncRegion>& regions, int region) {
  if (region < 0) return "L (ratio 1)";
  const AsyncRegion& r = regions[static_cast<std::size_t>(region)];
  return "'" + r.name + "' (ratio " + std::to_string(r.ratio) + ")";
}

}  // namespace

StepCounts::StepCounts(const TetMesh& mesh, const FreeDofs& freeDofs, std::vector<AsyncRegion> regions)
    : regions_(std::move(regions)) {
  if (freeDofs.numDofs() != mesh.numDofs()) {
    throw ValidationError("nested async regions: the free-DOF map has " + std::to_string(freeDofs.numDofs()) +
                          " DOFs but the mesh has " + std::to_string(mesh.numDofs()));
  }
  assignVertices(mesh, freeDofs);
  checkElements(mesh);
}

void StepCounts::assignVertices(const TetMesh& mesh, const FreeDofs& freeDofs) {
  vertexRegion_ = assignRegionVertices(regions_, mesh.numVertices());
  vertexCounts_.assign(vertexRegion_.size(), 1);
  std::vector<int> freeCount(regions_.size(), 0);
  for (std::size_t v = 0; v < vertexRegion_.size(); ++v) {
    const int region = vertexRegion_[v];
    if (region < 0) continue;
    vertexCounts_[v] = regions_[static_cast<std::size_t>(region)].ratio;
    for (int c = 0; c < 3; ++c)
      if (!freeDofs.isFixed(static_cast<int>(3 * v) + c)) ++freeCount[static_cast<std::size_t>(region)];
  }
  for (std::size_t i = 0; i < regions_.size(); ++i) {
    if (freeCount[i] == 0) {
      throw ValidationError("region '" + regions_[i].name +
                            "' has no free degree of freedom (empty, or every vertex fixed)");
    }
  }
  for (std::size_t v = 0; v < vertexCounts_.size(); ++v) {
    units_ = std::lcm(units_, static_cast<long long>(vertexCounts_[v]));
    if (units_ > kMaxUnits) {
      throw ValidationError("nested async regions: the least common multiple of the ratios exceeds " +
                            std::to_string(kMaxUnits) + " (at vertex " + std::to_string(v) +
                            "); use ratios that divide one another");
    }
  }
  const std::set<int> distinct(vertexCounts_.begin(), vertexCounts_.end());
  levels_.assign(distinct.begin(), distinct.end());
}

// Eq. N6: an element is evaluated on its fastest vertex's steps, so every slower vertex's
// step boundaries must be among them.
void StepCounts::checkElements(const TetMesh& mesh) {
  elementCounts_.assign(static_cast<std::size_t>(mesh.numElements()), 1);
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Eigen::Vector4i vertices = mesh.element(e);
    int fastest = 0, firstFast = -1;
    for (int a = 0; a < 4; ++a)
      if (vertexCounts_[static_cast<std::size_t>(vertices[a])] >
          vertexCounts_[static_cast<std::size_t>(vertices[fastest])])
        fastest = a;
    const int count = vertexCounts_[static_cast<std::size_t>(vertices[fastest])];
    for (int a = 0; a < 4; ++a) {
      const int region = vertexRegion_[static_cast<std::size_t>(vertices[a])];
      if (count % vertexCounts_[static_cast<std::size_t>(vertices[a])] != 0) {
        throw ValidationError(
            "element " + std::to_string(e) + " joins region " + describeRegion(regions_, region) + " and region " +
            describeRegion(regions_, vertexRegion_[static_cast<std::size_t>(vertices[fastest])]) +
            ": the ratios of regions that share an element must divide one another (e.g. 4 and 8, not 3 and 4)");
      }
      if (region >= 0 && firstFast >= 0 && region != firstFast) touching_ = true;
      if (region >= 0 && firstFast < 0) firstFast = region;
    }
    elementCounts_[static_cast<std::size_t>(e)] = count;
  }
}

std::string toString(NestedSolve solve) {
  switch (solve) {
    case NestedSolve::structured:
      return "structured";
    case NestedSolve::lu:
      return "lu";
    case NestedSolve::automatic:
      break;
  }
  return "automatic";
}

NestedSolve parseNestedSolve(const std::string& name) {
  for (NestedSolve s : {NestedSolve::automatic, NestedSolve::structured, NestedSolve::lu})
    if (toString(s) == name) return s;
  throw ValidationError("unknown nested solve '" + name + "' (expected automatic, structured or lu)");
}

NestedAsyncBackwardEuler::NestedAsyncBackwardEuler(DynamicSystem system, double largeTimestep,
                                                   std::vector<AsyncRegion> regions, NestedSolve solve)
    : Integrator(std::move(system), largeTimestep),
      counts_(meshOf(system_), system_.freeDofs, std::move(regions)),
      linear_(system_.forceModel->isLinear()) {
  Stopwatch setUp;
  setUp.start();
  hierarchy_ = std::make_unique<detail::HierarchySystem>(*system_.mesh, system_, counts_, solve);
  // Each region's summary: its vertices and the free DOFs outside it that share an element.
  const TetMesh& mesh = *system_.mesh;
  std::vector<std::set<int>> neighbours(static_cast<std::size_t>(counts_.numRegions()));
  std::vector<int> vertices(static_cast<std::size_t>(counts_.numRegions()), 0);
  for (int region : counts_.vertexRegion())
    if (region >= 0) ++vertices[static_cast<std::size_t>(region)];
  for (int e = 0; e < mesh.numElements(); ++e)
    for (int a = 0; a < 4; ++a) {
      const int region = counts_.vertexRegion()[static_cast<std::size_t>(mesh.element(e)[a])];
      if (region < 0) continue;
      for (int b = 0; b < 4; ++b)
        for (int c = 0; c < 3; ++c) {
          const int dof = 3 * mesh.element(e)[b] + c;
          if (counts_.vertexRegion()[static_cast<std::size_t>(dof / 3)] != region && !system_.freeDofs.isFixed(dof))
            neighbours[static_cast<std::size_t>(region)].insert(dof);
        }
    }
  for (int i = 0; i < counts_.numRegions(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    summaries_.push_back(
        {counts_.region(i).name, vertices[k], static_cast<int>(neighbours[k].size()), counts_.region(i).ratio});
  }
  setUpSeconds_ = setUp.stop();
}

NestedAsyncBackwardEuler::~NestedAsyncBackwardEuler() = default;

void NestedAsyncBackwardEuler::setTimestep(double timestep) {
  Integrator::setTimestep(timestep);
  built_ = false;
}

void NestedAsyncBackwardEuler::step() {
  if (!built_ || !linear_) {
    hierarchy_->build(displacement_, timestep(), stats_);
    built_ = true;
  }
  Stopwatch forces;
  forces.start();
  internalForce_.resize(displacement_.size());
  system_.forceModel->internalForces(displacement_, internalForce_);
  // f_ext where some DOF's step ends (Eq. N3): t_0 + k hL / units, the last one at t_1. The
  // vectors are kept from step to step (same units every step), so nothing is allocated.
  if (system_.externalForce) {
    const double t0 = time(), t1 = stepEndTime();
    const auto units = static_cast<double>(counts_.units());
    for (long long unit : hierarchy_->stepEndUnits()) {
      Eigen::VectorXd& f = external_[unit];
      evaluateExternalForce(unit == counts_.units() ? t1 : t0 + static_cast<double>(unit) * (timestep() / units), f);
    }
  }
  stats_.forceSeconds += forces.stop();
  hierarchy_->step(displacement_, velocity_, internalForce_, external_, newDisplacement_, newVelocity_, stats_);
  commitStep(newDisplacement_, newVelocity_);
}

RunReport NestedAsyncBackwardEuler::report() const {
  RunReport out;
  out.factorNonZeros = factorNonZeros();
  std::string levels;
  for (int count : counts_.levels()) levels += (levels.empty() ? "" : ", ") + std::to_string(count);
  char line[256];
  std::snprintf(line, sizeof line,
                "nested async regions: steps per large step %s; step system %lld unknowns; set-up %.3f s",
                levels.c_str(), unknowns(), setUpSeconds_);
  out.lines.emplace_back(line);
  out.lines.push_back("nested async regions: " + hierarchy_->solveDescription());
  return out;
}

std::vector<RegionSummary> NestedAsyncBackwardEuler::regionSummaries() const { return summaries_; }

int NestedAsyncBackwardEuler::regionOfVertex(int vertex) const {
  const std::vector<int>& region = counts_.vertexRegion();
  return vertex >= 0 && vertex < static_cast<int>(region.size()) ? region[static_cast<std::size_t>(vertex)] : -1;
}

long long NestedAsyncBackwardEuler::unknowns() const { return hierarchy_->unknowns(); }
long long NestedAsyncBackwardEuler::factorNonZeros() const { return hierarchy_->factorNonZeros(); }
bool NestedAsyncBackwardEuler::structuredSolve() const { return hierarchy_->structured(); }
Eigen::VectorXd NestedAsyncBackwardEuler::stepVelocities(int freeDof) const { return hierarchy_->velocities(freeDof); }
Eigen::VectorXd NestedAsyncBackwardEuler::stepDisplacements(int freeDof) const {
  return hierarchy_->displacements(freeDof);
}

}  // namespace asyncfem
