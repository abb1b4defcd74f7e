// SPDX-License-Identifier: BSD-3-Clause
// Internal to the tetMesher library: what a lattice offers the stuffing stages.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <concepts>
#include <cstdint>
#include <functional>
#include <vector>

namespace asyncfem::detail {

/// A lattice edge that a cut point may lie on, from `from` to `to`. The root finder starts
/// at `from`, so the direction is part of the lattice's (deterministic) output.
struct LatticeEdge {
  long long from = 0;
  long long to = 0;
};

/// What forEachTetrahedron accepts (the lattices take any callable of this signature, as a
/// template, so that the per-tetrahedron call inlines): one lattice tetrahedron, four
/// lattice vertex ids in the lattice's order.
using TetrahedronVisitor = std::function<void(const std::array<long long, 4>&)>;

/// The one interface through which the uniform lattice (BccLattice) and the graded one
/// (GradedTetrahedra) feed the single cut / warp / stencil pipeline (latticeCrossings.hpp,
/// stencils.hpp, stuffedMesh.hpp):
/// - vertex ids 0 .. numVertices()-1 with their position, their doubled integer lattice
///   coordinates (units of half a finest spacing; they decide long versus short edges and
///   the parity rule) and their colour (red: a finest cube centre);
/// - signChangingEdges(signs): every lattice edge whose ends have opposite signs, once, in a
///   fixed order (the order in which cut points compete to warp a vertex);
/// - forEachTetrahedron(visit): every lattice tetrahedron, in a fixed order (the order in
///   which output vertices are numbered), returning how many.
/// The uniform lattice computes all of this from indices and stores nothing; the graded one
/// stores its tetrahedra (and adds what only it needs: which tetrahedra are coarse, and the
/// cubes to refine when one of those meets the surface).
template <class Lattice>
concept StuffingLattice = requires(const Lattice& lattice, long long vertex, const std::vector<int>& signs,
                                   const TetrahedronVisitor& visit) {
  { lattice.numVertices() } -> std::convertible_to<long long>;
  { lattice.position(vertex) } -> std::convertible_to<Eigen::Vector3d>;
  { lattice.doubled(vertex) } -> std::convertible_to<Eigen::Vector3i>;
  { lattice.isRed(vertex) } -> std::convertible_to<bool>;
  { lattice.signChangingEdges(signs) } -> std::same_as<std::vector<LatticeEdge>>;
  { lattice.forEachTetrahedron(visit) } -> std::same_as<long long>;
};

/// One key per undirected lattice edge (ids fit in 32 bits, checked by checkLatticeSize, so
/// it is injective).
inline std::uint64_t edgeKey(long long a, long long b) {
  const auto lo = static_cast<std::uint64_t>(std::min(a, b));
  const auto hi = static_cast<std::uint64_t>(std::max(a, b));
  return (hi << 32) ^ lo ^ (hi >> 32);
}

/// -1, 0 or +1: inside, on the surface, outside.
inline int signOf(double value) { return value < 0.0 ? -1 : (value > 0.0 ? 1 : 0); }

}  // namespace asyncfem::detail
