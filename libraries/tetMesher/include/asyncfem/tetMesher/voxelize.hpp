// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Geometry>
#include <asyncfem/tetMesher/implicit.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>

namespace asyncfem {

/// Options of voxelize.
struct VoxelOptions {
  /// Material of every cube.
  Material material{"default", 1000.0, 1e6, 0.45};
  /// The most cubes a mesh may have (ValidationError above it, naming the count and a
  /// spacing that fits). A grid over the bounds with more than 8 maxCubes cells is refused
  /// before any inside test.
  long long maxCubes = 2'000'000;
  /// Evaluate the inside test on several threads (OpenMP).
  bool parallel = true;
};

/// What voxelize made.
struct VoxelReport {
  Eigen::Vector3i gridCells = Eigen::Vector3i::Zero();  ///< cells of the grid along x, y, z
  long long gridCellCount = 0;                          ///< their product
  int cubes = 0;
  int vertices = 0;
  double cubeVolume = 0.0;  ///< cubes * spacing^3
  double seconds = 0.0;     ///< wall time of voxelize
};

/// A hexahedral mesh of cubes of edge `spacing`: the cells of a regular grid whose centre is
/// inside the solid f < 0 (f as in implicit.hpp: SignedDistance::function() for a triangle
/// surface, with its pseudonormal or winding-number sign). The grid starts at bounds.min()
/// and has ceil(size / spacing) cells along each axis, so an axis-aligned box whose sides
/// are multiples of the spacing is filled exactly. Neighbouring cubes share their grid
/// vertices, so the mesh is conforming (every interior face belongs to exactly two cubes);
/// vertices and cubes are numbered in grid order (x fastest, then y, then z), each cube in
/// the vertex order of hexahedron.hpp (positive Jacobian). ValidationError for a
/// non-positive or non-finite spacing, an empty box, a grid or cube count over the cap
/// (VoxelOptions::maxCubes), a non-finite value of f, or no cube at all (the message names
/// the spacing and the box).
TetMesh voxelize(const ImplicitFunction& f, const Eigen::AlignedBox3d& bounds, double spacing,
                 const VoxelOptions& options = {}, VoxelReport* report = nullptr);

/// (cubeVolume - enclosedVolume) / enclosedVolume: the relative volume error of the cube
/// boundary against the volume the surface encloses (ValidationError unless enclosedVolume > 0).
double relativeVolumeError(double cubeVolume, double enclosedVolume);

}  // namespace asyncfem
