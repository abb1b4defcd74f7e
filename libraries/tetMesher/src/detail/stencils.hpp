// SPDX-License-Identifier: BSD-3-Clause
// Internal to the tetMesher library: step 4 of isosurface stuffing, the stencils.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "detail/lattice.hpp"
#include "detail/latticeCrossings.hpp"

namespace asyncfem::detail {

/// The mesh the stencils build: output vertices numbered on first use.
struct StencilOutput {
  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector4i> elements;  ///< positively oriented
  std::vector<long long> sources;         ///< lattice vertex of each output vertex, -1 for cut points
  int cutPointsUsed = 0;
};

/// Builds the output mesh tetrahedron by tetrahedron from a lattice and where the surface
/// crosses it (signs after warping, warped positions, cut points).
template <StuffingLattice Lattice>
class StencilBuilder {
 public:
  StencilBuilder(const Lattice& lattice, const LatticeCrossings& crossings)
      : lattice_(lattice), crossings_(crossings) {}

  /// Fills the part of lattice tetrahedron `tet` where f <= 0 with the stencil of its sign
  /// pattern (Labelle & Shewchuk 2007, Figure 4; - inside, 0 on the surface, + outside).
  /// No inside vertex: nothing (this includes tetrahedra whose four vertices all lie on
  /// the surface, which the stencils discard).
  void fill(const std::array<long long, 4>& tet);

  const StencilOutput& output() const { return out_; }
  StencilOutput release() { return std::move(out_); }

 private:
  enum class Diagonal { Forward, Backward, Free };
  /// The vertices of a lattice tetrahedron grouped by sign (inside, on the surface, outside).
  struct SignGroups {
    std::array<long long, 4> neg{}, zero{}, pos{};
    int numNeg = 0, numZero = 0, numPos = 0;
  };

  void fillOneInside(const SignGroups& g);
  void fillPyramid(const SignGroups& g);
  void fillTwoInsideTwoOutside(const SignGroups& g);
  void fillThreeInside(const SignGroups& g);
  Eigen::Vector3d position(long long v) const;
  int lat(long long v);
  int cut(long long u, long long v);
  bool diagonalAtFirst(long long A, long long B, long long P) const;
  void emit(int a, int b, int c, int d);
  void emitPyramid(int x, const std::array<int, 4>& q, bool diagonal02);
  void emitPrism(const std::array<int, 3>& a, const std::array<int, 3>& b, std::array<Diagonal, 3> diagonals);
  Diagonal freeDiagonal(const std::array<int, 3>& a, const std::array<int, 3>& b,
                        const std::array<Diagonal, 3>& diagonals, int i) const;

  const Lattice& lattice_;
  const LatticeCrossings& crossings_;
  StencilOutput out_;
  std::unordered_map<long long, int> latticeOutput_;
  std::unordered_map<std::uint64_t, int> cutOutput_;
};

}  // namespace asyncfem::detail
