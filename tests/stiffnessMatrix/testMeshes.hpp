// SPDX-License-Identifier: BSD-3-Clause
// Small meshes shared by the stiffnessMatrix tests.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <random>

namespace asyncfem::test {

/// Unit box of cells^3 cubes with three materials: the default one, a stiff, dense slab
/// x < 0.5 and a soft, nearly incompressible corner; the regions follow cell boundaries
/// when cells is a multiple of 4, so their volumes are exact.
inline TetMesh mixedMaterialBox(int cells) {
  BoxMeshSpec spec;
  spec.cells = Eigen::Vector3i::Constant(cells);
  spec.material = Material{"default", 1000.0, 1e6, 0.3};
  spec.regions.push_back({"slab", Eigen::Vector3d(-1.0, -1.0, -1.0), Eigen::Vector3d(0.5, 2.0, 2.0),
                          Material{"stiff", 7800.0, 2e9, 0.25}});
  spec.regions.push_back({"corner", Eigen::Vector3d(0.75, 0.75, 0.75), Eigen::Vector3d(2.0, 2.0, 2.0),
                          Material{"soft", 300.0, 5e4, 0.49}});
  return makeBoxMesh(spec);
}

/// Box of cells^3 cubes (one material) whose interior vertices are moved randomly by up
/// to 0.2 cell widths per coordinate, small enough to keep every element positively
/// oriented. The box's faces stay planar, so its volume stays size^3.
inline TetMesh perturbedBox(int cells, unsigned seed, const Material& material = Material{"m", 1200.0, 3e5, 0.4}) {
  BoxMeshSpec spec;
  spec.cells = Eigen::Vector3i::Constant(cells);
  spec.size = Eigen::Vector3d(2.0, 1.5, 1.0);
  spec.material = material;
  const TetMesh box = makeBoxMesh(spec);
  Eigen::Matrix3Xd x = box.restPositions();
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> offset(-0.2, 0.2);
  for (int v = 0; v < x.cols(); ++v) {
    for (int c = 0; c < 3; ++c) {
      const double cell = spec.size[c] / cells;
      const double t = x(c, v) / spec.size[c];
      if (t > 1e-9 && t < 1.0 - 1e-9) x(c, v) += offset(random) * cell;
    }
  }
  return TetMesh(x, box.elements(), box.materials(), box.elementMaterials());
}

/// The six rigid-body modes (3n x 6): translations along x, y, z, then infinitesimal
/// rotations omega x (X - centroid) about the three axes.
inline Eigen::MatrixXd rigidBodyModes(const TetMesh& mesh) {
  const int n = mesh.numVertices();
  const Eigen::Vector3d centroid = mesh.restPositions().rowwise().mean();
  Eigen::MatrixXd modes = Eigen::MatrixXd::Zero(3 * n, 6);
  for (int v = 0; v < n; ++v) {
    const Eigen::Vector3d p = mesh.restPosition(v) - centroid;
    for (int c = 0; c < 3; ++c) {
      modes((3 * v) + c, c) = 1.0;
      const Eigen::Vector3d rotated = Eigen::Vector3d::Unit(c).cross(p);
      modes.block<3, 1>(3 * v, 3 + c) = rotated;
    }
  }
  return modes;
}

}  // namespace asyncfem::test
