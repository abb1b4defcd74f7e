// SPDX-License-Identifier: BSD-3-Clause
// Meshes, deformations and rotations shared by the corotationalLinearFEM tests.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <random>
#include <vector>

#include "../common/forceModelTestHelpers.hpp"

namespace asyncfem::test {

/// Young's modulus and the edge length of the cubes of smallBox(); the force scale of
/// one vertex at unit strain is about youngsModulus * cellSize^2.
inline constexpr double kYoungsModulus = 2e6;

/// A box of cells^3 cubes (6 tets each), 1 x 0.8 x 0.6, E = kYoungsModulus, nu = 0.4.
inline TetMesh smallBox(int cells) {
  BoxMeshSpec spec;
  spec.size = Eigen::Vector3d(1.0, 0.8, 0.6);
  spec.cells = Eigen::Vector3i::Constant(cells);
  spec.material = Material{"m", 1000.0, kYoungsModulus, 0.4};
  return makeBoxMesh(spec);
}

/// Largest cell edge of smallBox(cells).
inline double cellSize(int cells) { return 1.0 / cells; }

/// Displacement (3n) of the rigid motion x = Q X + t.
inline Eigen::VectorXd rigidDisplacement(const TetMesh& mesh, const Eigen::Matrix3d& rotation,
                                         const Eigen::Vector3d& translation) {
  Eigen::VectorXd u(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v) {
    const Eigen::Vector3d x = mesh.restPosition(v);
    u.segment<3>(3 * v) = rotation * x + translation - x;
  }
  return u;
}

/// max_i |a_i - b_i|; the tests divide it by a stated physical scale (forces of size
/// E h^2 are far from 1, so max(1, |a|, |b|) would not be a meaningful reference).
inline double maxAbsDifference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).cwiseAbs().maxCoeff();
}

}  // namespace asyncfem::test
