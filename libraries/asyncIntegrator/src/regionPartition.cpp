// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/vertexSelection.hpp>
#include <numeric>
#include <set>
#include <string>

namespace asyncfem {

namespace {

void sortUnique(std::vector<int>& ids) {
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
}

}  // namespace

std::vector<int> regionVertices(const TetMesh& mesh, const RegionSelector& selector) {
  if (selector.boxMin.size() != selector.boxMax.size()) {
    throw ValidationError("region selector: every box needs both a min and a max corner");
  }
  // The one vertex-selection resolver of volumetricMesh; sets of either kind.
  VertexSelection selection;
  selection.sets = selector.vertexSets;
  selection.sets.insert(selection.sets.end(), selector.elementSets.begin(), selector.elementSets.end());
  for (std::size_t b = 0; b < selector.boxMin.size(); ++b)
    selection.boxes.push_back({selector.boxMin[b], selector.boxMax[b]});
  selection.vertices = selector.vertices;
  try {
    return selectVertices(mesh, selection);
  } catch (const SelectionError& error) {
    // Name the selector's own list: its vertex sets come first in selection.sets.
    const int vertexSets = static_cast<int>(selector.vertexSets.size());
    if (error.part() == "sets" && error.index() >= vertexSets) {
      throw SelectionError("elementSets", error.index() - vertexSets, error.what());
    }
    throw SelectionError(error.part() == "sets" ? "vertexSets" : error.part(), error.index(), error.what());
  }
}

RegionPartition::RegionPartition(const TetMesh& mesh, const FreeDofs& freeDofs, std::vector<AsyncRegion> regions)
    : regions_(std::move(regions)) {
  const int n = mesh.numVertices();
  if (freeDofs.numDofs() != 3 * n) {
    throw ValidationError("region partition: the free-DOF map has " + std::to_string(freeDofs.numDofs()) +
                          " DOFs but the mesh has " + std::to_string(3 * n));
  }
  assignVertices(n);
  countSteps(mesh);
  splitFreeDofs(freeDofs, classifyElements(mesh));
}

std::vector<int> assignRegionVertices(std::vector<AsyncRegion>& regions, int numVertices) {
  std::vector<int> vertexRegion(static_cast<std::size_t>(numVertices), -1);
  for (std::size_t i = 0; i < regions.size(); ++i) {
    AsyncRegion& r = regions[i];
    if (r.name.empty()) r.name = std::string("S").append(std::to_string(i + 1));
    if (r.ratio < 1) {
      throw ValidationError("region '" + r.name + "': ratio m = " + std::to_string(r.ratio) +
                            " (hL / hS) must be an integer >= 1");
    }
    sortUnique(r.vertices);
    for (int v : r.vertices) {
      if (v < 0 || v >= numVertices) {
        throw ValidationError("region '" + r.name + "': vertex " + std::to_string(v) + " outside [0, " +
                              std::to_string(numVertices) + ")");
      }
      int& owner = vertexRegion[static_cast<std::size_t>(v)];
      if (owner >= 0) {
        throw ValidationError("regions '" + regions[static_cast<std::size_t>(owner)].name + "' and '" + r.name +
                              "' overlap: vertex " + std::to_string(v) + " is in both");
      }
      owner = static_cast<int>(i);
    }
  }
  return vertexRegion;
}

void RegionPartition::assignVertices(int numVertices) { vertexRegion_ = assignRegionVertices(regions_, numVertices); }

namespace {
std::string describeRegion(const std::vector<AsyncRegion>& regions, int region) {
  if (region < 0) return "L (ratio 1)";
  const AsyncRegion& r = regions[static_cast<std::size_t>(region)];
  return "'" + r.name + "' (ratio " + std::to_string(r.ratio) + ")";
}
}  // namespace

// Eq. N6: an element is evaluated on its fastest vertex's steps, so every slower vertex's
// step boundaries must be among them.
void RegionPartition::countSteps(const TetMesh& mesh) {
  vertexCounts_.assign(vertexRegion_.size(), 1);
  for (std::size_t v = 0; v < vertexRegion_.size(); ++v)
    if (vertexRegion_[v] >= 0) vertexCounts_[v] = regions_[static_cast<std::size_t>(vertexRegion_[v])].ratio;
  elementCounts_.assign(static_cast<std::size_t>(mesh.numElements()), 1);
  for (int e = 0; e < mesh.numElements(); ++e) {
    int fastest = mesh.elementVertex(e, 0), firstFast = -1;
    for (int a = 1; a < mesh.verticesPerElement(); ++a) {
      const int v = mesh.elementVertex(e, a);
      if (vertexCounts_[static_cast<std::size_t>(v)] > vertexCounts_[static_cast<std::size_t>(fastest)]) fastest = v;
    }
    const int count = vertexCounts_[static_cast<std::size_t>(fastest)];
    for (int a = 0; a < mesh.verticesPerElement(); ++a) {
      const int v = mesh.elementVertex(e, a);
      const int region = vertexRegion_[static_cast<std::size_t>(v)];
      if (count % vertexCounts_[static_cast<std::size_t>(v)] != 0) {
        throw ValidationError(
            "element " + std::to_string(e) + " joins region " + describeRegion(regions_, region) + " and region " +
            describeRegion(regions_, vertexRegion_[static_cast<std::size_t>(fastest)]) +
            ": the ratios of regions that share an element must divide one another (e.g. 4 and 8, not 3 and 4)");
      }
      if (region >= 0 && firstFast >= 0 && region != firstFast) {
        if (touchingElement_ < 0) {
          touchingElement_ = e;
          touchingRegions_ = {firstFast, region};
        }
        if (regions_[static_cast<std::size_t>(region)].ratio == regions_[static_cast<std::size_t>(firstFast)].ratio)
          equalRatioContacts_.emplace_back(std::min(region, firstFast), std::max(region, firstFast));
      }
      if (region >= 0 && firstFast < 0) firstFast = region;
    }
    elementCounts_[static_cast<std::size_t>(e)] = count;
  }
  for (const int count : vertexCounts_) {
    if (units_ == 0) break;
    units_ = std::lcm(units_, static_cast<long long>(count));
    if (units_ > kMaxUnits) units_ = 0;
  }
  const std::set<int> distinct(vertexCounts_.begin(), vertexCounts_.end());
  levels_.assign(distinct.begin(), distinct.end());
}

std::vector<AsyncRegion> RegionPartition::regionsMergedAtOneRatio() const {
  if (equalRatioContacts_.empty()) return {};
  std::vector<int> root(regions_.size());
  std::iota(root.begin(), root.end(), 0);
  const auto find = [&root](int i) {
    while (root[static_cast<std::size_t>(i)] != i) i = root[static_cast<std::size_t>(i)];
    return i;
  };
  for (const auto& [a, b] : equalRatioContacts_) {
    const int ra = find(a), rb = find(b);
    if (ra != rb) root[static_cast<std::size_t>(std::max(ra, rb))] = std::min(ra, rb);
  }
  std::vector<AsyncRegion> merged;
  std::vector<int> slot(regions_.size(), -1);
  for (std::size_t i = 0; i < regions_.size(); ++i) {
    int& s = slot[static_cast<std::size_t>(find(static_cast<int>(i)))];
    if (s < 0) {
      s = static_cast<int>(merged.size());
      merged.push_back(regions_[i]);
      continue;
    }
    AsyncRegion& into = merged[static_cast<std::size_t>(s)];
    into.name += "+" + regions_[i].name;
    into.vertices.insert(into.vertices.end(), regions_[i].vertices.begin(), regions_[i].vertices.end());
  }
  for (AsyncRegion& region : merged) sortUnique(region.vertices);
  return merged;
}

void RegionPartition::requireSeparated(const std::string& who) const {
  if (!touching()) return;
  throw ValidationError(who + ": element " + std::to_string(touchingElement_) + " has vertices in regions '" +
                        regions_[static_cast<std::size_t>(touchingRegions_.first)].name + "' and '" +
                        regions_[static_cast<std::size_t>(touchingRegions_.second)].name +
                        "': fast regions must be separated by at least one element layer of L");
}

// Interface elements join L and a fast region (or two fast regions); each fast region's
// interface is the DOFs of L its elements reach.
std::vector<std::vector<char>> RegionPartition::classifyElements(const TetMesh& mesh) {
  std::vector<std::vector<char>> touchesRegion(static_cast<std::size_t>(numRegions()),
                                               std::vector<char>(static_cast<std::size_t>(mesh.numDofs()), 0));
  for (int e = 0; e < mesh.numElements(); ++e) {
    bool hasLarge = false;
    std::vector<int> fast;
    for (int a = 0; a < mesh.verticesPerElement(); ++a) {
      const int region = vertexRegion_[static_cast<std::size_t>(mesh.elementVertex(e, a))];
      if (region < 0) {
        hasLarge = true;
      } else if (std::find(fast.begin(), fast.end(), region) == fast.end()) {
        fast.push_back(region);
      }
    }
    if (fast.empty() || (!hasLarge && fast.size() == 1)) continue;
    interfaceElements_.push_back(e);
    if (!hasLarge) continue;
    for (const int region : fast)
      for (int a = 0; a < mesh.verticesPerElement(); ++a) {
        const int v = mesh.elementVertex(e, a);
        if (vertexRegion_[static_cast<std::size_t>(v)] >= 0) continue;
        for (int c = 0; c < 3; ++c)
          touchesRegion[static_cast<std::size_t>(region)][static_cast<std::size_t>(3 * v + c)] = 1;
      }
  }
  return touchesRegion;
}

void RegionPartition::splitFreeDofs(const FreeDofs& freeDofs, const std::vector<std::vector<char>>& touchesRegion) {
  regionDofs_.assign(static_cast<std::size_t>(numRegions()), {});
  interfaceDofs_.assign(static_cast<std::size_t>(numRegions()), {});
  interfacePositions_.assign(static_cast<std::size_t>(numRegions()), {});
  for (int dof : freeDofs.freeToFull()) {
    const int region = vertexRegion_[static_cast<std::size_t>(dof / 3)];
    if (region >= 0) {
      regionDofs_[static_cast<std::size_t>(region)].push_back(dof);
      continue;
    }
    const int position = static_cast<int>(largeDofs_.size());
    largeDofs_.push_back(dof);
    for (int i = 0; i < numRegions(); ++i) {
      if (touchesRegion[static_cast<std::size_t>(i)][static_cast<std::size_t>(dof)]) {
        interfaceDofs_[static_cast<std::size_t>(i)].push_back(dof);
        interfacePositions_[static_cast<std::size_t>(i)].push_back(position);
      }
    }
  }
  for (int i = 0; i < numRegions(); ++i) {
    if (regionDofs_[static_cast<std::size_t>(i)].empty()) {
      throw ValidationError("region '" + regions_[static_cast<std::size_t>(i)].name +
                            "' has no free degree of freedom (empty, or every vertex fixed)");
    }
  }
}

RegionPartition mergeTouchingAtOneRatio(const TetMesh& mesh, const FreeDofs& freeDofs, RegionPartition partition) {
  std::vector<AsyncRegion> merged = partition.regionsMergedAtOneRatio();
  if (merged.empty()) return partition;
  return RegionPartition(mesh, freeDofs, std::move(merged));
}

std::vector<RegionSummary> summarizeRegions(const RegionPartition& partition) {
  std::vector<int> vertexCount(static_cast<std::size_t>(partition.numRegions()), 0);
  for (const int region : partition.vertexRegion()) {
    if (region >= 0) ++vertexCount[static_cast<std::size_t>(region)];
  }
  std::vector<RegionSummary> summaries;
  for (int i = 0; i < partition.numRegions(); ++i) {
    summaries.push_back({partition.region(i).name, vertexCount[static_cast<std::size_t>(i)],
                         static_cast<int>(partition.interfaceDofs(i).size()), partition.ratio(i)});
  }
  return summaries;
}

void growByRings(const TetMesh& mesh, std::vector<char>& marked, int rings) {
  for (int ring = 0; ring < rings; ++ring) {
    std::vector<char> grown = marked;
    for (int e = 0; e < mesh.numElements(); ++e) {
      bool any = false;
      for (int a = 0; a < mesh.verticesPerElement(); ++a)
        any = any || marked[static_cast<std::size_t>(mesh.elementVertex(e, a))];
      if (any)
        for (int a = 0; a < mesh.verticesPerElement(); ++a)
          grown[static_cast<std::size_t>(mesh.elementVertex(e, a))] = 1;
    }
    marked.swap(grown);
  }
}

}  // namespace asyncfem
