// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <string>
#include <vector>

namespace asyncfem {

/// An axis-aligned box region that assigns a material to the elements whose centroid
/// lies inside it (later regions win) and defines an element set and a vertex set
/// (vertices of those elements) under `name`.
struct BoxRegion {
  std::string name;
  Eigen::Vector3d min;
  Eigen::Vector3d max;
  Material material;
};

/// A box [origin, origin + size] cut into cells x cells y cells z cubes, each split into
/// six tetrahedra (Kuhn/Freudenthal split along the main diagonal, so faces match across
/// cells and the mesh is conforming). Every element is positively oriented.
/// Elements get `material` unless a BoxRegion claims them. Also creates vertex sets
/// "xmin", "xmax", "ymin", "ymax", "zmin", "zmax" (vertices on each face of the box).
struct BoxMeshSpec {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d size = Eigen::Vector3d::Ones();
  Eigen::Vector3i cells = Eigen::Vector3i::Constant(4);
  Material material{"default", 1000.0, 1e6, 0.45};
  std::vector<BoxRegion> regions;
};
TetMesh makeBoxMesh(const BoxMeshSpec& spec);

/// Cantilever beam along +x: length x height x depth with cellsAlongLength cells along x
/// (cross-section cells chosen to keep cubes near-regular). The last tipFraction of its
/// length is a separate material "tip" (element set "tip"); the rest is "body". Vertex set
/// "root" = the x = 0 face (to fix), "tip" = vertices of tip elements.
struct BeamSpec {
  double length = 1.0, height = 0.2, depth = 0.2;
  int cellsAlongLength = 20;
  double tipFraction = 0.2;
  Material body{"body", 1000.0, 1e6, 0.45};
  Material tip{"tip", 200.0, 5e7, 0.45};
};
TetMesh makeBeamMesh(const BeamSpec& spec);

/// A box of lattice cells [begin, end) (integer cell coordinates, end exclusive) of a
/// CellMeshSpec, with its material. Its elements form the element set `name` and their
/// vertices the vertex set `name`; blocks with the same name share both sets (and must
/// give the same material).
struct CellBlock {
  std::string name;
  Eigen::Vector3i begin = Eigen::Vector3i::Zero();
  Eigen::Vector3i end = Eigen::Vector3i::Ones();
  Material material;
};

/// A vertex set `name` = every mesh vertex within `rings` lattice cells (Chebyshev distance
/// on the lattice) of a vertex of the sets named in `around`: e.g. an appendage plus one
/// ring of body vertices around its foot, a fast region that keeps the interface elements
/// soft (shared design note on asynchronous coupling).
struct CellVertexRing {
  std::string name;
  std::vector<std::string> around;
  int rings = 1;
};

/// A union of cubic lattice cells of edge cellSize, cell (i, j, k) spanning
/// origin + cellSize * [(i, j, k), (i + 1, j + 1, k + 1)]: each occupied cell is split into
/// six tetrahedra exactly as in makeBoxMesh (one Freudenthal split for the whole lattice),
/// so any union of blocks is conforming: neighbouring cells share their lattice vertices
/// and face triangulations. A cell claimed by several blocks belongs to the last one.
/// Lattice vertices no cell uses are dropped; vertices and elements are numbered in
/// lattice order (x fastest, then y, then z). Every element is positively oriented.
/// Sets: per block name (elements and vertices), per CellVertexRing (vertices), and the
/// vertex set "bottom" = the vertices on the lowest occupied y layer (y up: the ground).
/// ValidationError for an empty spec, an empty block, a non-positive cell size, a name
/// used with two materials, or a ring around an unknown set.
struct CellMeshSpec {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double cellSize = 0.05;
  std::vector<CellBlock> blocks;
  std::vector<CellVertexRing> vertexRings;
};
TetMesh makeCellMesh(const CellMeshSpec& spec);

/// The antenna on a block (shared design note, "A scene where it wins"), y up: a block of
/// blockCells cells clamped on its bottom face (y = 0) and a rod of one cell cross-section
/// and rodCells cells standing on its top face, on cell (blockCells.x / 2, blockCells.z / 2).
/// Element and vertex sets "block" and "rod"; vertex sets "bottom" (to fix), "rodTip" (the
/// rod's top four vertices) and "rodAndRing" (the rod plus one ring of block vertices
/// around its foot: the fast region).
///
/// With whipCells > 0 the rod's top whipCells cells are a lighter "whip" (element and
/// vertex set "whip", material `whip`; "rod" keeps the cells below it) for nested regions:
/// "rodAndRing" then holds rod, whip and ring, and "rodAndRingBelowWhip" the same without
/// the whip's vertices (the outer region when the whip is the inner one).
struct AntennaSpec {
  double cellSize = 0.05;
  Eigen::Vector3i blockCells{10, 4, 10};
  int rodCells = 8;
  Material block{"block", 1000.0, 1e6, 0.3};
  Material rod{"rod", 100.0, 1e6, 0.3};
  int whipCells = 0;  ///< 0 <= whipCells < rodCells
  Material whip{"whip", 10.0, 1e6, 0.3};
};
TetMesh makeAntennaMesh(const AntennaSpec& spec = {});

/// A blocky snail, y up, head towards +x, 0.8 m long: a sole ("sole", clamped through
/// "bottom"), a stepped shell ("shell") on its back half, a neck and head ("head") on its
/// front, and two light, soft eye tentacles ("tentacles", one cell cross-section,
/// tentacleCells cells tall) on the head.
/// Vertex sets: those of the element sets, "bottom" (to fix), "tentacleTips" (the top
/// vertices of both tentacles) and "tentaclesAndRing" (the tentacles plus one ring of head
/// vertices around their feet: the fast region).
struct SnailSpec {
  double cellSize = 0.05;
  int tentacleCells = 6;
  Material body{"body", 1000.0, 1e6, 0.3};
  Material shell{"shell", 1000.0, 5e6, 0.3};
  Material tentacles{"tentacles", 100.0, 2e5, 0.3};
};
TetMesh makeSnailMesh(const SnailSpec& spec = {});

}  // namespace asyncfem
