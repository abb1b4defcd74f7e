// SPDX-License-Identifier: BSD-3-Clause
// Internal to the tetMesher library: steps 1 to 3 of isosurface stuffing, on any lattice.
#pragma once

#include <Eigen/Core>
#include <asyncfem/tetMesher/isosurfaceStuffing.hpp>
#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

#include "detail/lattice.hpp"

namespace asyncfem::detail {

/// Where the surface crosses a lattice: the sign of every lattice vertex after warping
/// (-1 inside, 0 on the surface, +1 outside), the warped vertices' new positions and the
/// cut points (by edgeKey) on the sign-changing edges.
struct LatticeCrossings {
  std::vector<int> signs;
  std::unordered_map<long long, Eigen::Vector3d> warped;
  std::unordered_map<std::uint64_t, Eigen::Vector3d> cuts;
};

/// ValidationError when a lattice of numVertices vertices exceeds options.maxLatticeVertices
/// (or the 32-bit ids that edgeKey needs).
void checkLatticeSize(long long numVertices, const MesherOptions& options);

/// Fills `value` for vertex `v` and returns true when f there is already known.
using KnownValue = std::function<bool(long long v, double& value)>;

/// Step 1: f at every lattice vertex (on all threads when `parallel`), known values reused;
/// ValidationError for a non-finite value.
template <StuffingLattice Lattice>
std::vector<double> sampleLattice(const ImplicitFunction& f, const Lattice& lattice, bool parallel,
                                  const KnownValue& known = {});

/// Steps 2 and 3: a cut point (the root of f, Illinois regula falsi from the edge's `from`
/// end) on every sign-changing edge (roots found on all threads when options.parallel),
/// then every vertex closer to a cut point on one of its edges than alpha times the edge's
/// length (alphaLong on axis-parallel edges, alphaShort on diagonal ones) moved onto the
/// closest such cut point, the first in the lattice's edge order on a tie.
template <StuffingLattice Lattice>
LatticeCrossings cutAndWarp(const ImplicitFunction& f, const Lattice& lattice, const std::vector<double>& values,
                            const MesherOptions& options);

}  // namespace asyncfem::detail
