// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/volumetricMesh/tetMesh.hpp>

#include <Eigen/Core>

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

}  // namespace asyncfem
