// SPDX-License-Identifier: BSD-3-Clause
// Isosurface stuffing (Labelle & Shewchuk 2007) as one pipeline over two lattices. The
// uniform BCC lattice (detail/bccLattice.hpp) and the graded one (detail/gradedLattice.hpp)
// offer the same interface (detail/lattice.hpp, StuffingLattice), and both go through the
// same stages: sampling, cut points and warping (detail/latticeCrossings.hpp), then
// stencils, pinch repair, angle guard and checks (detail/stuffedMesh.hpp). The uniform
// lattice is not the graded one with zero levels: it stores nothing (its ids, edges and
// tetrahedra follow from indices), which is what lets it reach 10^8 vertices, and its edge
// and tetrahedron order define the shipped meshes. The graded front end adds only what
// grading needs: reusing f at known points, and refining cubes where a coarse tetrahedron
// meets the surface.
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/isosurfaceStuffing.hpp>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include "detail/bccLattice.hpp"
#include "detail/gradedGrid.hpp"
#include "detail/gradedLattice.hpp"
#include "detail/latticeCrossings.hpp"
#include "detail/stuffedMesh.hpp"

namespace asyncfem {

namespace {

using detail::GradedGrid;
using detail::GradedLattice;

TetMesh stuffUniform(const ImplicitFunction& f, const Eigen::AlignedBox3d& bounds, double spacing,
                     const MesherOptions& options, StuffingReport* report) {
  const detail::BccLattice lattice(bounds, spacing);
  detail::checkLatticeSize(lattice.numVertices(), options);
  const std::vector<double> values = detail::sampleLattice(f, lattice, options.parallel);
  detail::LatticeCrossings crossings = detail::cutAndWarp(f, lattice, values, options);
  return detail::assembleStuffedMesh(lattice, values, crossings, spacing, options, report);
}

/// f at every vertex of a graded lattice; values known from earlier lattices (`known`, keyed
/// by packed doubled coordinates) are reused, and the new ones added to it.
std::vector<double> sampleGradedLattice(const ImplicitFunction& f, const GradedLattice& lattice,
                                        std::unordered_map<std::uint64_t, double>& known, bool parallel) {
  const std::vector<double> values = detail::sampleLattice(f, lattice, parallel, [&](long long v, double& value) {
    const auto it = known.find(GradedGrid::packKey(lattice.doubled(v)));
    if (it == known.end()) return false;
    value = it->second;
    return true;
  });
  for (long long v = 0; v < lattice.numVertices(); ++v)
    known.emplace(GradedGrid::packKey(lattice.doubled(v)), values[static_cast<std::size_t>(v)]);
  return values;
}

TetMesh stuffGraded(const ImplicitFunction& f, const Eigen::AlignedBox3d& bounds, double spacing,
                    const MesherOptions& options, StuffingReport* report) {
  // Every leaf cube brings about one black and one red lattice vertex: the cube count is
  // held to the lattice vertex limit.
  const long long maxCells = std::min<long long>(options.maxLatticeVertices, std::numeric_limits<std::int32_t>::max());
  GradedGrid grid = GradedGrid::covering(bounds, spacing, options.gradingLevels, maxCells);
  // Every point within one spacing of the surface gets a finest cube (for a 1-Lipschitz f,
  // as distances are). That keeps every tetrahedron outside the finest lattice at least half
  // a spacing from the surface, beyond the reach of warping (alphaShort * sqrt(3)/2 < 0.36
  // spacings); what a non-distance f hides is caught below and refined.
  grid.refineNear(f, spacing, options.parallel);
  std::unordered_map<std::uint64_t, double> known = grid.values();
  for (int rounds = 0;; ++rounds) {
    const GradedLattice lattice(grid);
    detail::checkLatticeSize(lattice.numVertices(), options);
    const std::vector<double> values = sampleGradedLattice(f, lattice, known, options.parallel);
    detail::LatticeCrossings crossings = detail::cutAndWarp(f, lattice, values, options);
    const std::vector<int> toSplit = lattice.leavesMeetingSurface(crossings.signs);
    if (!toSplit.empty()) {
      if (grid.splitLeaves(toSplit) == 0) {
        throw Error("stuffIsosurface: internal error: the surface meets a coarse cube that cannot be refined");
      }
      continue;
    }
    TetMesh mesh = detail::assembleStuffedMesh(lattice, values, crossings, spacing, options, report);
    if (report != nullptr) {
      report->gradingLevels = options.gradingLevels;
      report->latticeCells = grid.numLeaves();
      report->refinementRounds = rounds;
    }
    return mesh;
  }
}

}  // namespace

TetMesh stuffIsosurface(const ImplicitFunction& f, const Eigen::AlignedBox3d& bounds, double spacing,
                        const MesherOptions& options, StuffingReport* report) {
  if (!(spacing > 0.0) || !std::isfinite(spacing)) {
    throw ValidationError("stuffIsosurface: spacing must be a finite number > 0, got " + std::to_string(spacing));
  }
  if (bounds.isEmpty() || !bounds.min().allFinite() || !bounds.max().allFinite()) {
    throw ValidationError("stuffIsosurface: empty or non-finite bounds");
  }
  if (!f) throw ValidationError("stuffIsosurface: no implicit function");
  if (options.gradingLevels < 0 || options.gradingLevels > kMaxGradingLevels) {
    throw ValidationError("stuffIsosurface: gradingLevels must be between 0 and " + std::to_string(kMaxGradingLevels) +
                          ", got " + std::to_string(options.gradingLevels));
  }
  if (options.gradingLevels == 0) return stuffUniform(f, bounds, spacing, options, report);
  return stuffGraded(f, bounds, spacing, options, report);
}

}  // namespace asyncfem
