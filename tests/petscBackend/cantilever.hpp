// SPDX-License-Identifier: BSD-3-Clause
// The PETSc tests' mesh.
#pragma once

#include <asyncfem/volumetricMesh/generators.hpp>

namespace asyncfem::test {

/// A 1 x 0.2 x 0.2 cantilever (12 x 3 x 3 cubes, 648 tets, 208 vertices) of soft rubber;
/// the tests fix its x = 0 face ("xmin"): under gravity its tip sags by ~0.1 in 0.5 s,
/// rotations large enough that corotational and linear FEM differ visibly.
inline TetMesh rubberCantilever() {
  BoxMeshSpec spec;
  spec.size = Eigen::Vector3d(1.0, 0.2, 0.2);
  spec.cells = Eigen::Vector3i(12, 3, 3);
  spec.material = Material{"rubber", 1000.0, 1e6, 0.45};
  return makeBoxMesh(spec);
}

}  // namespace asyncfem::test
