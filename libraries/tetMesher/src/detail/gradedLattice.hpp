// SPDX-License-Identifier: BSD-3-Clause
// Internal to the tetMesher library: the graded lattice of isosurface stuffing.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "detail/gradedGrid.hpp"
#include "detail/lattice.hpp"

namespace asyncfem::detail {

/// Tetrahedra of a graded body-centred cubic grid (a StuffingLattice; Labelle & Shewchuk
/// 2007, Section 6), built from the leaves of a GradedGrid: across a face between two leaves
/// of one size, the tetrahedra of the red edge joining their centres with each edge of the
/// face (bisected where a smaller cube put a vertex at the edge's midpoint); across a face
/// towards smaller leaves, the pyramid from the centre to the face split into eight at the
/// face's centre and edge midpoints; across a face towards a larger leaf, that pyramid split
/// into two by the diagonal through the larger face's centre, which is how the larger side
/// splits it. Vertex ids: cube corners (black) first, then cube centres (red).
struct GradedLattice {
  explicit GradedLattice(const GradedGrid& grid);

  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double spacing = 0.0;
  std::vector<Eigen::Vector3i> doubledCoordinates;  ///< per vertex
  std::vector<std::array<long long, 4>> tetrahedra;
  /// Per tetrahedron: true for a tetrahedron of the finest uniform BCC lattice (two
  /// face-adjacent finest cube centres and an edge of their shared face). Only those may be
  /// cut by the surface or touch a warped vertex; the others are kept whole or dropped.
  std::vector<char> plain;
  /// Per tetrahedron: the octree leaves it was made from (the second is -1 for a pyramid
  /// inside one cube).
  std::vector<std::array<int, 2>> owners;

  long long numVertices() const { return static_cast<long long>(doubledCoordinates.size()); }
  Eigen::Vector3i doubled(long long id) const { return doubledCoordinates[static_cast<std::size_t>(id)]; }
  /// Red vertices of the finest lattice are the finest cube centres: all doubled coordinates odd.
  bool isRed(long long id) const {
    const Eigen::Vector3i& d = doubledCoordinates[static_cast<std::size_t>(id)];
    return (d.x() & 1) != 0 && (d.y() & 1) != 0 && (d.z() & 1) != 0;
  }
  Eigen::Vector3d position(long long id) const {
    return origin + 0.5 * spacing * doubledCoordinates[static_cast<std::size_t>(id)].cast<double>();
  }
  /// Sign-changing edges of the finest (plain) tetrahedra, lower id first, in the order of
  /// their first tetrahedron; coarse tetrahedra are never cut (leavesMeetingSurface).
  std::vector<LatticeEdge> signChangingEdges(const std::vector<int>& signs) const;
  template <class Visit>
  long long forEachTetrahedron(Visit&& visit) const {
    for (const auto& tet : tetrahedra) visit(tet);
    return static_cast<long long>(tetrahedra.size());
  }
  /// The stencils' guarantee covers the finest tetrahedra only: every other one must lie
  /// strictly on one side of the surface, untouched by warping (signs after warping). The
  /// leaves of those that do not, sorted, to be refined; empty when the lattice is usable.
  std::vector<int> leavesMeetingSurface(const std::vector<int>& signs) const;
};

}  // namespace asyncfem::detail
