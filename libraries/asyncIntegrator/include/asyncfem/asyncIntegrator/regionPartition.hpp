// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <asyncfem/volumetricMesh/vertexSelection.hpp>
#include <string>
#include <utility>
#include <vector>

namespace asyncfem {

/// One fast region S_i: a set of vertices advanced with the small timestep
/// hS_i = hL / ratio. Everything not in any fast region is the large-step region L.
struct AsyncRegion {
  std::string name;
  std::vector<int> vertices;  ///< 0-based vertex ids (any order; duplicates ignored)
  int ratio = 1;              ///< m_i = hL / hS_i, a positive integer
};

/// Ways to name the vertices of a region in a scene (resolved by regionVertices()).
struct RegionSelector {
  std::vector<std::string> vertexSets;   ///< named vertex sets of the mesh
  std::vector<std::string> elementSets;  ///< every vertex of every element of these sets
  std::vector<Eigen::Vector3d> boxMin;   ///< axis-aligned boxes (rest positions inside, inclusive)
  std::vector<Eigen::Vector3d> boxMax;
  std::vector<int> vertices;  ///< explicit 0-based ids
};
/// Union of everything the selector names, sorted and unique, through the mesh's one
/// resolver (selectVertices). Unknown set names, empty sets, boxes selecting nothing and
/// out-of-range ids throw asyncfem::SelectionError whose part is the selector's list
/// ("vertexSets", "elementSets", "boxes", "vertices") and index its position there.
std::vector<int> regionVertices(const TetMesh& mesh, const RegionSelector& selector);

/// Region of every vertex (-1: none) for regions given by their vertices: names unnamed
/// regions "S1", "S2", ... and sorts their vertices. Throws asyncfem::ValidationError for a
/// ratio < 1, a vertex id out of range and a vertex in two regions (naming both).
std::vector<int> assignRegionVertices(std::vector<AsyncRegion>& regions, int numVertices);

/// A validated partition of the free DOFs into fast regions S_1..S_n and the rest L,
/// with what both step solvers need: the interface data of the two-level structured solve
/// and the step counts of the hierarchy solve (docs/asynchronous-integrator.md, "Method"
/// and "Nested and touching regions"). Built once per set-up.
///
/// Regions may touch one another and nest (an element with vertices in two fast regions):
/// then touching() is true and only the hierarchy solve applies; integrators that couple
/// each S_i only to L call requireSeparated(). Rejected with asyncfem::ValidationError
/// (message names the culprit):
/// - a ratio < 1;
/// - a vertex listed in two regions (names the vertex and both regions);
/// - an element whose vertices' ratios do not divide one another (Eq. N6; names the
///   element, its regions and their ratios);
/// - a region with no free DOF (all its vertices fixed, or empty);
/// - a vertex id out of range.
class RegionPartition {
 public:
  RegionPartition(const TetMesh& mesh, const FreeDofs& freeDofs, std::vector<AsyncRegion> regions);

  int numRegions() const { return static_cast<int>(regions_.size()); }
  const AsyncRegion& region(int i) const { return regions_[static_cast<std::size_t>(i)]; }
  int ratio(int i) const { return region(i).ratio; }

  /// Free DOFs of S_i as global DOF ids (ascending).
  const std::vector<int>& regionDofs(int i) const { return regionDofs_[static_cast<std::size_t>(i)]; }
  /// Free DOFs of L as global DOF ids (ascending).
  const std::vector<int>& largeDofs() const { return largeDofs_; }
  /// Free DOFs of L that share an element with S_i (global ids, ascending): the only
  /// columns of H^{S_i L} and rows of H^{L S_i} that are non-zero.
  const std::vector<int>& interfaceDofs(int i) const { return interfaceDofs_[static_cast<std::size_t>(i)]; }
  /// Positions of interfaceDofs(i) inside largeDofs().
  const std::vector<int>& interfacePositions(int i) const { return interfacePositions_[static_cast<std::size_t>(i)]; }
  /// Elements with vertices in more than one region (L counts as a region).
  const std::vector<int>& interfaceElements() const { return interfaceElements_; }
  /// Region of every vertex: i for S_i, -1 for L.
  const std::vector<int>& vertexRegion() const { return vertexRegion_; }
  /// Steps per large step of every vertex: its region's ratio, 1 in L.
  const std::vector<int>& vertexCounts() const { return vertexCounts_; }
  /// Steps per large step of every element: its fastest vertex's count (Eq. N6).
  const std::vector<int>& elementCounts() const { return elementCounts_; }
  /// The distinct step counts, ascending (1 first when L has a vertex): the levels.
  const std::vector<int>& levels() const { return levels_; }
  /// Least common multiple of every count: the large step in time units of the hierarchy
  /// solve; 0 when it exceeds kMaxUnits (ratios that do not divide one another).
  long long units() const { return units_; }
  static constexpr long long kMaxUnits = 1LL << 20;
  /// Whether an element has vertices in two different fast regions (regions that touch or
  /// nest): only the hierarchy solve applies then.
  bool touching() const { return touchingElement_ >= 0; }
  /// Throws asyncfem::ValidationError naming the first element with vertices in two fast
  /// regions, for a solve that couples each S_i only to L (who: the integrator or solve).
  void requireSeparated(const std::string& who) const;
  /// The regions with every pair that touches at one ratio (an element joins them, their
  /// ratios are equal) merged into one region (vertices united, names joined by "+"): the
  /// same step counts, so the same step (Eqs. N1-N6 depend on the counts alone), and where
  /// no other regions touch, a partition the two-level solve runs. Empty when no two
  /// regions touch at one ratio.
  std::vector<AsyncRegion> regionsMergedAtOneRatio() const;

  /// vertexRegion()[vertex], or -1 for a vertex out of range.
  int regionOfVertex(int vertex) const {
    return vertex >= 0 && vertex < static_cast<int>(vertexRegion_.size())
               ? vertexRegion_[static_cast<std::size_t>(vertex)]
               : -1;
  }

 private:
  /// vertexRegion_ from the regions (names defaulted, ratios and vertices checked).
  void assignVertices(int numVertices);
  /// Every vertex's and element's step count, the levels and the time units (Eq. N6
  /// checked per element).
  void countSteps(const TetMesh& mesh);
  /// interfaceElements_, and per region which DOFs of L its interface elements touch.
  std::vector<std::vector<char>> classifyElements(const TetMesh& mesh);
  /// regionDofs_, largeDofs_, interfaceDofs_ and interfacePositions_ from the free DOFs.
  void splitFreeDofs(const FreeDofs& freeDofs, const std::vector<std::vector<char>>& touchesRegion);

  std::vector<AsyncRegion> regions_;
  std::vector<std::vector<int>> regionDofs_;
  std::vector<int> largeDofs_;
  std::vector<std::vector<int>> interfaceDofs_;
  std::vector<std::vector<int>> interfacePositions_;
  std::vector<int> interfaceElements_;
  std::vector<int> vertexRegion_;
  std::vector<int> vertexCounts_, elementCounts_, levels_;
  long long units_ = 1;
  int touchingElement_ = -1;                             // first element with vertices in two fast regions
  std::vector<std::pair<int, int>> equalRatioContacts_;  // regions an element joins at one ratio
  std::pair<int, int> touchingRegions_{-1, -1};
};

/// partition with every pair of regions that touch at one ratio merged
/// (RegionPartition::regionsMergedAtOneRatio), rebuilt on mesh and freeDofs; partition
/// itself when no two regions touch at one ratio. What AsyncBackwardEuler solves.
RegionPartition mergeTouchingAtOneRatio(const TetMesh& mesh, const FreeDofs& freeDofs, RegionPartition partition);

/// Marks every vertex that shares an element with a marked one (marked: one entry per
/// vertex), `rings` times: how the region policies grow a vertex set.
void growByRings(const TetMesh& mesh, std::vector<char>& marked, int rings);

/// One RegionSummary per fast region of partition (name, vertices, interface DOFs, m).
std::vector<RegionSummary> summarizeRegions(const RegionPartition& partition);

}  // namespace asyncfem
