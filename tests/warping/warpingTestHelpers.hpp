// SPDX-License-Identifier: BSD-3-Clause
// Meshes and displacement fields shared by the warping tests.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <cmath>
#include <set>
#include <utility>

#include "../hexElements/hexBar.hpp"

namespace asyncfem::testing {

/// A 2 x 1 x 1 box of 4 x 2 x 2 cubes (96 tets), off the origin so that rotations about
/// the origin and about the centroid differ.
inline TetMesh warpingTestBox() {
  BoxMeshSpec spec;
  spec.origin = Eigen::Vector3d(0.3, -0.2, 0.1);
  spec.size = Eigen::Vector3d(2.0, 1.0, 1.0);
  spec.cells = Eigen::Vector3i(4, 2, 2);
  return makeBoxMesh(spec);
}

/// test::hexBar(2) (8 x 2 x 2 cubes of 0.125 over [0, 1] x [0, 0.25]^2) with its interior
/// vertices moved by up to wobble along a smooth non-affine field (general hexahedra for
/// wobble > 0).
inline TetMesh warpingTestHexBar(double wobble) {
  const TetMesh bar = test::hexBar(2);
  Eigen::Matrix3Xd x = bar.restPositions();
  for (int v = 0; v < bar.numVertices(); ++v) {
    const Eigen::Vector3d p = x.col(v);
    if (p.x() > 0.0 && p.x() < 1.0 && p.y() > 0.0 && p.y() < 0.25 && p.z() > 0.0 && p.z() < 0.25) {
      x.col(v) += wobble * Eigen::Vector3d(std::sin(13.0 * p.x()), std::cos(11.0 * p.x()), std::sin(17.0 * p.x()));
    }
  }
  return {std::move(x), bar.hexahedra(), bar.materials(), bar.elementMaterials()};
}

/// Stacked 3n vector of field(X) over the rest positions.
template <class Field>
Eigen::VectorXd sampleField(const TetMesh& mesh, const Field& field) {
  Eigen::VectorXd u(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v) {
    u.segment<3>(3 * v) = field(Eigen::Vector3d(mesh.restPosition(v)));
  }
  return u;
}

/// The linearised field of the rigid rotation by angle theta about axis through center:
/// u = theta [axis]x (X - center), the first-order term of (R - I)(X - center). Its
/// linear result X + u stretches every direction perpendicular to the axis by
/// sqrt(1 + theta^2).
inline Eigen::VectorXd linearizedRotation(const TetMesh& mesh, double theta, const Eigen::Vector3d& axis,
                                          const Eigen::Vector3d& center) {
  const Eigen::Vector3d a = axis.normalized();
  return sampleField(mesh, [&](const Eigen::Vector3d& x) -> Eigen::Vector3d { return theta * a.cross(x - center); });
}

/// The exact displacement (R - I)(X - center) of the same rotation.
inline Eigen::VectorXd rigidRotation(const TetMesh& mesh, double theta, const Eigen::Vector3d& axis,
                                     const Eigen::Vector3d& center) {
  const Eigen::Matrix3d r = Eigen::AngleAxisd(theta, axis.normalized()).toRotationMatrix();
  return sampleField(mesh, [&](const Eigen::Vector3d& x) -> Eigen::Vector3d {
    return (r - Eigen::Matrix3d::Identity()) * (x - center);
  });
}

/// Largest relative change of an element edge's length (tetrahedra or hexahedra), max |l - L| / L, for positions
/// rest + displacement.
inline double maxEdgeLengthError(const TetMesh& mesh, const Eigen::VectorXd& displacement) {
  std::set<std::pair<int, int>> edges;
  auto addEdge = [&](int e, int a, int b) {
    const int i = mesh.elementVertex(e, a);
    const int j = mesh.elementVertex(e, b);
    edges.emplace(std::min(i, j), std::max(i, j));
  };
  for (int e = 0; e < mesh.numElements(); ++e) {
    if (mesh.isHexahedral()) {
      // The twelve edges, each on two of the faces.
      for (const auto& f : hexahedron::kFaces)
        for (std::size_t c = 0; c < 4; ++c) addEdge(e, f[c], f[(c + 1) % 4]);
      continue;
    }
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) addEdge(e, a, b);
  }
  double worst = 0.0;
  for (const auto& [i, j] : edges) {
    const Eigen::Vector3d restEdge = mesh.restPosition(j) - mesh.restPosition(i);
    const Eigen::Vector3d edge = restEdge + displacement.segment<3>(3 * j) - displacement.segment<3>(3 * i);
    worst = std::max(worst, std::abs(edge.norm() - restEdge.norm()) / restEdge.norm());
  }
  return worst;
}

/// Centroid (plain mean) of rest + displacement.
inline Eigen::Vector3d meanPosition(const TetMesh& mesh, const Eigen::VectorXd& displacement) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int v = 0; v < mesh.numVertices(); ++v) {
    sum += mesh.restPosition(v) + displacement.segment<3>(3 * v);
  }
  return sum / mesh.numVertices();
}

}  // namespace asyncfem::testing
