// SPDX-License-Identifier: BSD-3-Clause
// Run-time regions: docs/asynchronous-integrator.md, section "Run-time regions".
#include <algorithm>
#include <asyncfem/asyncIntegrator/runTimeRegions.hpp>
#include <asyncfem/core/error.hpp>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>

namespace asyncfem {

namespace {

/// Ratio of every vertex under `regions` (0: L).
std::vector<int> vertexRatios(int numVertices, const std::vector<AsyncRegion>& regions) {
  std::vector<int> ratio(static_cast<std::size_t>(numVertices), 0);
  for (const AsyncRegion& region : regions)
    for (int v : region.vertices) ratio[static_cast<std::size_t>(v)] = region.ratio;
  return ratio;
}

int countFast(const std::vector<AsyncRegion>& regions) {
  int count = 0;
  for (const AsyncRegion& region : regions) count += static_cast<int>(region.vertices.size());
  return count;
}

int findRoot(std::vector<int>& parent, int i) {
  while (parent[static_cast<std::size_t>(i)] != i) {
    parent[static_cast<std::size_t>(i)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    i = parent[static_cast<std::size_t>(i)];
  }
  return i;
}

/// Regions that share a vertex or an element merged into one (vertices united, the larger
/// ratio, names joined by "+"), in order of their first member.
std::vector<AsyncRegion> mergeTouching(const TetMesh& mesh, const std::vector<AsyncRegion>& regions) {
  const auto count = static_cast<int>(regions.size());
  std::vector<int> parent(static_cast<std::size_t>(count));
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<int> owner(static_cast<std::size_t>(mesh.numVertices()), -1);
  const auto unite = [&](int a, int b) { parent[static_cast<std::size_t>(findRoot(parent, a))] = findRoot(parent, b); };
  for (int i = 0; i < count; ++i)
    for (int v : regions[static_cast<std::size_t>(i)].vertices) {
      int& o = owner[static_cast<std::size_t>(v)];
      if (o >= 0) unite(i, o);
      o = i;
    }
  for (int e = 0; e < mesh.numElements(); ++e) {
    int first = -1;
    for (int a = 0; a < mesh.verticesPerElement(); ++a) {
      const int o = owner[static_cast<std::size_t>(mesh.elementVertex(e, a))];
      if (o < 0) continue;
      if (first < 0) {
        first = o;
      } else {
        unite(first, o);
      }
    }
  }
  std::vector<AsyncRegion> merged;
  std::vector<int> slot(static_cast<std::size_t>(count), -1);
  for (int i = 0; i < count; ++i) {
    const int root = findRoot(parent, i);
    const AsyncRegion& region = regions[static_cast<std::size_t>(i)];
    int& s = slot[static_cast<std::size_t>(root)];
    if (s < 0) {
      s = static_cast<int>(merged.size());
      merged.push_back(region);
      continue;
    }
    AsyncRegion& into = merged[static_cast<std::size_t>(s)];
    into.name += "+" + region.name;
    into.ratio = std::max(into.ratio, region.ratio);
    into.vertices.insert(into.vertices.end(), region.vertices.begin(), region.vertices.end());
  }
  for (AsyncRegion& region : merged) {
    std::sort(region.vertices.begin(), region.vertices.end());
    region.vertices.erase(std::unique(region.vertices.begin(), region.vertices.end()), region.vertices.end());
  }
  return merged;
}

/// Regions kept at their own ratios (RunTimeRegionOptions::nest): each vertex goes to the
/// fastest region that claims it (the earlier one among equals), regions left without a
/// vertex vanish; where an element joins two regions whose ratios do not divide one
/// another (Eq. N6), every touching region is merged instead (mergeTouching).
std::vector<AsyncRegion> nestTouching(const TetMesh& mesh, const std::vector<AsyncRegion>& regions) {
  std::vector<int> owner(static_cast<std::size_t>(mesh.numVertices()), -1);
  for (int i = 0; i < static_cast<int>(regions.size()); ++i)
    for (int v : regions[static_cast<std::size_t>(i)].vertices) {
      int& o = owner[static_cast<std::size_t>(v)];
      if (o < 0 || regions[static_cast<std::size_t>(o)].ratio < regions[static_cast<std::size_t>(i)].ratio) o = i;
    }
  for (int e = 0; e < mesh.numElements(); ++e) {
    int fastest = 1;
    for (int a = 0; a < mesh.verticesPerElement(); ++a) {
      const int o = owner[static_cast<std::size_t>(mesh.elementVertex(e, a))];
      if (o >= 0) fastest = std::max(fastest, regions[static_cast<std::size_t>(o)].ratio);
    }
    for (int a = 0; a < mesh.verticesPerElement(); ++a) {
      const int o = owner[static_cast<std::size_t>(mesh.elementVertex(e, a))];
      if (o >= 0 && fastest % regions[static_cast<std::size_t>(o)].ratio != 0) return mergeTouching(mesh, regions);
    }
  }
  std::vector<AsyncRegion> out;
  for (int i = 0; i < static_cast<int>(regions.size()); ++i) {
    AsyncRegion region{regions[static_cast<std::size_t>(i)].name, {}, regions[static_cast<std::size_t>(i)].ratio};
    for (int v = 0; v < mesh.numVertices(); ++v)
      if (owner[static_cast<std::size_t>(v)] == i) region.vertices.push_back(v);
    if (!region.vertices.empty()) out.push_back(std::move(region));
  }
  return out;
}

/// The vertices an indicator marks (ratio > 0), one region per set connected through
/// elements, at the largest ratio its vertices want.
std::vector<AsyncRegion> indicatorComponents(const TetMesh& mesh, const std::vector<int>& ratio) {
  const auto n = static_cast<int>(ratio.size());
  std::vector<int> parent(static_cast<std::size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  for (int e = 0; e < mesh.numElements(); ++e) {
    int first = -1;
    for (int a = 0; a < mesh.verticesPerElement(); ++a) {
      const int vertex = mesh.elementVertex(e, a);
      if (ratio[static_cast<std::size_t>(vertex)] == 0) continue;
      if (first < 0) {
        first = vertex;
      } else {
        parent[static_cast<std::size_t>(findRoot(parent, vertex))] = findRoot(parent, first);
      }
    }
  }
  std::vector<AsyncRegion> components;
  std::vector<int> slot(static_cast<std::size_t>(n), -1);
  for (int vertex = 0; vertex < n; ++vertex) {
    if (ratio[static_cast<std::size_t>(vertex)] == 0) continue;
    int& s = slot[static_cast<std::size_t>(findRoot(parent, vertex))];
    if (s < 0) {
      s = static_cast<int>(components.size());
      components.push_back({"indicator" + std::to_string(s), {}, 1});
    }
    AsyncRegion& component = components[static_cast<std::size_t>(s)];
    component.vertices.push_back(vertex);
    component.ratio = std::max(component.ratio, ratio[static_cast<std::size_t>(vertex)]);
  }
  return components;
}

}  // namespace

RunTimeRegionPolicy::RunTimeRegionPolicy(const TetMesh& mesh, const FreeDofs& freeDofs, RunTimeRegionOptions options)
    : mesh_(&mesh), options_(std::move(options)) {
  const RunTimeRegionOptions& o = options_;
  if (o.contactRatio < 1) throw ValidationError("run-time regions: contact ratio must be >= 1");
  if (!(o.contactMargin >= 0.0) || !(o.contactLookahead >= 0.0) || o.contactRings < 0 || o.contactSlack < 0) {
    throw ValidationError("run-time regions: contact margin, lookahead, rings and slack must be >= 0");
  }
  if (o.indicator && (!(o.indicatorTolerance > 0.0) || o.indicatorRatio < 2 || o.indicatorRings < 0)) {
    throw ValidationError("run-time regions: indicator tolerance must be > 0, ratio >= 2 and rings >= 0");
  }
  if (o.minDwell < 0 || !(o.shrinkFactor >= 1.0) || o.cacheSize < 0) {
    throw ValidationError("run-time regions: minDwell and cache must be >= 0 and shrink >= 1");
  }
  for (std::size_t w = 0; w < o.schedule.size(); ++w) {
    const ScheduledRegion& window = o.schedule[w];
    const std::string where = "run-time regions: schedule[" + std::to_string(w) + "]";
    if (!(window.end > window.start)) throw ValidationError(where + ": end must be after start");
    if (window.ratio < 1) throw ValidationError(where + ": ratio must be >= 1");
    for (int v : window.vertices) {
      if (v < 0 || v >= mesh.numVertices()) {
        throw ValidationError(where + ": vertex " + std::to_string(v) + " out of range (the mesh has " +
                              std::to_string(mesh.numVertices()) + " vertices)");
      }
    }
  }
  hasFreeDof_.assign(static_cast<std::size_t>(mesh.numVertices()), 0);
  const std::vector<int>& fullToFree = freeDofs.fullToFree();
  for (std::size_t dof = 0; dof < fullToFree.size(); ++dof)
    if (fullToFree[dof] >= 0) hasFreeDof_[dof / 3] = 1;
  if (o.loads) {
    loads_.emplace(mesh, hasFreeDof_,
                   LoadsPolicySettings{o.loadsRatio, o.loadsRings, o.loadsParts, o.loadsRelease, o.minDwell,
                                       o.loadsNeighbourhood});
  }
}

void RunTimeRegionPolicy::setExternalForce(ExternalForceFunction force, ExternalForceChanges changes) {
  if (loads_) loads_->setExternalForce(std::move(force), std::move(changes));
}

const std::vector<LoadsSwitch>& RunTimeRegionPolicy::loadsSwitches() const {
  static const std::vector<LoadsSwitch> none;
  return loads_ ? loads_->switches() : none;
}

std::vector<char> RunTimeRegionPolicy::contactVertices(double largeStep, const Eigen::VectorXd& u,
                                                       const Eigen::VectorXd& v, const ObstacleProximity& proximity,
                                                       int rings) const {
  std::vector<char> marked(static_cast<std::size_t>(mesh_->numVertices()), 0);
  if (!options_.contact || !proximity) return marked;
  std::vector<int> near;
  proximity(u, options_.contactMargin, near);
  for (int vertex : near) marked[static_cast<std::size_t>(vertex)] = 1;
  if (options_.contactLookahead > 0.0) {
    const Eigen::VectorXd predicted = u + (options_.contactLookahead * largeStep) * v;
    proximity(predicted, options_.contactMargin, near);
    for (int vertex : near) marked[static_cast<std::size_t>(vertex)] = 1;
  }
  if (std::find(marked.begin(), marked.end(), 1) != marked.end()) growByRings(*mesh_, marked, rings);
  return marked;
}

void RunTimeRegionPolicy::recordVelocity(double time, const Eigen::VectorXd& v) {
  if (!options_.indicator) return;
  if (time == lastRecorded_ && !velocities_.empty()) {
    velocities_.back() = v;  // the same boundary again (a set-up before its first step)
    return;
  }
  if (time < lastRecorded_) velocities_.clear();  // not a continuation: start over
  velocities_.push_back(v);
  if (velocities_.size() > 3) velocities_.erase(velocities_.begin());
  lastRecorded_ = time;
}

// Eq. (R1): e_v = |v_k - 2 v_{k-1} + v_{k-2}| / 2 against tolerance times the RMS speed.
std::vector<int> RunTimeRegionPolicy::indicatorRatios(int extraRings) const {
  const auto n = static_cast<std::size_t>(mesh_->numVertices());
  std::vector<int> ratio(n, 0);
  if (!options_.indicator || velocities_.size() < 3) return ratio;
  const Eigen::VectorXd& v = velocities_[2];
  const Eigen::VectorXd change = 0.5 * (v - 2.0 * velocities_[1] + velocities_[0]);
  double sumSquares = 0.0;
  int moving = 0;
  for (std::size_t vertex = 0; vertex < n; ++vertex) {
    if (!hasFreeDof_[vertex]) continue;
    sumSquares += v.segment<3>(3 * static_cast<Eigen::Index>(vertex)).squaredNorm();
    ++moving;
  }
  const double speed = moving > 0 ? std::sqrt(sumSquares / moving) : 0.0;
  if (!(speed > 0.0)) return ratio;
  bool any = false;
  for (std::size_t vertex = 0; vertex < n; ++vertex) {
    if (!hasFreeDof_[vertex]) continue;
    const double want =
        change.segment<3>(3 * static_cast<Eigen::Index>(vertex)).norm() / (options_.indicatorTolerance * speed);
    if (!(want > 1.0)) continue;
    int m = 2;
    while (m < options_.indicatorRatio && m < want) m *= 2;
    ratio[vertex] = std::min(m, options_.indicatorRatio);
    any = true;
  }
  if (!any) return ratio;
  // Grow: every vertex of an element takes the largest ratio of the element's vertices.
  for (int ring = 0; ring < options_.indicatorRings + extraRings; ++ring) {
    std::vector<int> grown = ratio;
    for (int e = 0; e < mesh_->numElements(); ++e) {
      int largest = 0;
      for (int a = 0; a < mesh_->verticesPerElement(); ++a)
        largest = std::max(largest, ratio[static_cast<std::size_t>(mesh_->elementVertex(e, a))]);
      if (largest == 0) continue;
      for (int a = 0; a < mesh_->verticesPerElement(); ++a) {
        int& r = grown[static_cast<std::size_t>(mesh_->elementVertex(e, a))];
        r = std::max(r, largest);
      }
    }
    ratio.swap(grown);
  }
  return ratio;
}

std::vector<int> RunTimeRegionPolicy::activeWindows(double time) const {
  std::vector<int> active;
  for (std::size_t w = 0; w < options_.schedule.size(); ++w) {
    const ScheduledRegion& window = options_.schedule[w];
    if (time >= window.start && time < window.end) active.push_back(static_cast<int>(w));
  }
  return active;
}

std::vector<AsyncRegion> RunTimeRegionPolicy::assemble(double time, const std::vector<char>& contact,
                                                       const std::vector<int>& indicated) const {
  std::vector<AsyncRegion> regions;
  for (int w : activeWindows(time)) {
    const ScheduledRegion& window = options_.schedule[static_cast<std::size_t>(w)];
    regions.push_back(
        {window.name.empty() ? "schedule" + std::to_string(w) : window.name, window.vertices, window.ratio});
  }
  if (loads_)
    for (AsyncRegion& part : loads_->regions()) regions.push_back(std::move(part));
  AsyncRegion touching{"contact", {}, options_.contactRatio};
  for (std::size_t vertex = 0; vertex < contact.size(); ++vertex)
    if (contact[vertex]) touching.vertices.push_back(static_cast<int>(vertex));
  if (!touching.vertices.empty()) regions.push_back(std::move(touching));
  for (AsyncRegion& component : indicatorComponents(*mesh_, indicated)) regions.push_back(std::move(component));
  std::vector<AsyncRegion> merged = options_.nest ? nestTouching(*mesh_, regions) : mergeTouching(*mesh_, regions);
  // Vertices without a free DOF take no substeps; a region of only such vertices is none.
  std::vector<AsyncRegion> out;
  for (AsyncRegion& region : merged) {
    region.vertices.erase(std::remove_if(region.vertices.begin(), region.vertices.end(),
                                         [&](int vertex) { return !hasFreeDof_[static_cast<std::size_t>(vertex)]; }),
                          region.vertices.end());
    if (!region.vertices.empty() && region.ratio > 1) out.push_back(std::move(region));
  }
  return out;
}

std::vector<AsyncRegion> RunTimeRegionPolicy::wanted(double time, double largeStep, const Eigen::VectorXd& u,
                                                     const Eigen::VectorXd& v,
                                                     const ObstacleProximity& proximity) const {
  return assemble(time, contactVertices(largeStep, u, v, proximity, options_.contactRings), indicatorRatios(0));
}

namespace {
/// Whether every vertex gets at least the ratio it wants (per-vertex ratios, 0: none).
bool covers(const std::vector<int>& have, const std::vector<int>& want) {
  for (std::size_t vertex = 0; vertex < have.size(); ++vertex)
    if (have[vertex] < want[vertex]) return false;
  return true;
}
/// Whether every vertex gets at least the ratio `needed` gives it under `regions`.
bool covers(int numVertices, const std::vector<AsyncRegion>& regions, const std::vector<AsyncRegion>& needed) {
  return covers(vertexRatios(numVertices, regions), vertexRatios(numVertices, needed));
}
}  // namespace

bool RunTimeRegionPolicy::canServe(const std::vector<AsyncRegion>& regions, const std::vector<AsyncRegion>& proposal,
                                   double time, double largeStep, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                   const ObstacleProximity& proximity) const {
  if (static_cast<double>(countFast(regions)) > options_.shrinkFactor * countFast(proposal)) return false;
  const int n = mesh_->numVertices();
  const std::vector<int> have = vertexRatios(n, regions);
  const std::vector<int> want = vertexRatios(
      n, assemble(time, contactVertices(largeStep, u, v, proximity, options_.contactRings), indicatorRatios(0)));
  if (!covers(have, want)) return false;
  // Windows open and close exactly: on a window's vertices (open or closed now) a stand-in
  // must give the ratio the policy gives them now, neither fewer substeps nor more.
  for (const ScheduledRegion& window : options_.schedule)
    for (const int vertex : window.vertices)
      if (have[static_cast<std::size_t>(vertex)] != want[static_cast<std::size_t>(vertex)]) return false;
  // So do the loads policy's parts: fast exactly while the policy holds them fast.
  if (loads_)
    for (const int vertex : loads_->partVertices())
      if (have[static_cast<std::size_t>(vertex)] != want[static_cast<std::size_t>(vertex)]) return false;
  return true;
}

std::optional<std::vector<AsyncRegion>> RunTimeRegionPolicy::decide(double time, double largeStep,
                                                                    const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                                                    const ObstacleProximity& proximity,
                                                                    const std::vector<AsyncRegion>& current,
                                                                    long long stepsKept, std::string& reason) {
  const int n = mesh_->numVertices();
  recordVelocity(time, v);
  std::string loadsReason;
  const bool loadsChanged = loads_ && loads_->update(time, largeStep, u, v, loadsReason);
  const std::vector<char> needed = contactVertices(largeStep, u, v, proximity, options_.contactRings);
  const std::vector<int> indicated = indicatorRatios(0);
  std::vector<char> generous = needed;
  if (std::find(generous.begin(), generous.end(), 1) != generous.end())
    growByRings(*mesh_, generous, options_.contactSlack);
  std::vector<AsyncRegion> proposal = assemble(time, generous, indicatorRatios(1));
  const std::vector<int> windows = activeWindows(time);
  const std::vector<int> currentRatio = vertexRatios(n, current);
  const std::vector<int> proposedRatio = vertexRatios(n, proposal);
  if (currentRatio == proposedRatio) {
    started_ = true;
    lastWindows_ = windows;
    return std::nullopt;
  }
  if (!started_ || windows != lastWindows_ || loadsChanged) {
    // Windows and the loads policy switch exactly when they say, whatever the dwell.
    reason = loadsChanged ? loadsReason : "";
    if (started_ && windows != lastWindows_)
      reason += (reason.empty() ? "" : "; ") + std::string("schedule window opens or closes");
    if (reason.empty()) reason = "initial regions";
  } else {
    // Replace at once when the regions in use miss a vertex a policy needs (or give it
    // fewer substeps); otherwise only after the dwell, and only to shrink by a margin.
    const std::vector<int> none(static_cast<std::size_t>(n), 0);
    const char* shrinks = !options_.indicator ? "contact region shrinks"
                          : options_.contact  ? "regions shrink"
                                              : "indicator region shrinks";
    if (!covers(n, current, assemble(time, needed, none))) {
      reason = "contact region grows";
    } else if (!covers(n, current, assemble(time, needed, indicated))) {
      reason = "indicator region grows";
    } else if (stepsKept >= options_.minDwell &&
               static_cast<double>(countFast(current)) > options_.shrinkFactor * countFast(proposal)) {
      reason = proposal.empty() ? (options_.indicator ? "regions end" : "contact ends") : shrinks;
    } else {
      return std::nullopt;
    }
  }
  started_ = true;
  lastWindows_ = windows;
  return proposal;
}

void appendRepartitionLines(const std::vector<RepartitionRecord>& records, std::vector<std::string>& lines) {
  int reused = 0;
  double seconds = 0.0;
  for (const RepartitionRecord& r : records) {
    reused += r.reused ? 1 : 0;
    seconds += r.seconds;
  }
  char line[320];
  std::snprintf(line, sizeof(line), "run-time regions: %zu re-partitions (%d from the set-up cache), %.3f s of set-up",
                records.size(), reused, seconds);
  lines.emplace_back(line);
  constexpr std::size_t kShown = 10;
  for (std::size_t k = 0; k < records.size(); ++k) {
    if (records.size() > 2 * kShown && k == kShown) {
      lines.push_back("  ... " + std::to_string(records.size() - 2 * kShown) + " more ...");
      k = records.size() - kShown;
    }
    const RepartitionRecord& r = records[k];
    std::snprintf(line, sizeof(line),
                  "  t = %.4f s (step %lld): %s -> %d region(s), %d fast vertices, |I| %d DOFs, %d moved, %s %.1f ms",
                  r.time, r.step, r.reason.c_str(), r.regions, r.fastVertices, r.interfaceDofs, r.movedVertices,
                  r.reused ? "reused," : "set-up", 1000.0 * r.seconds);
    lines.emplace_back(line);
  }
}

}  // namespace asyncfem
