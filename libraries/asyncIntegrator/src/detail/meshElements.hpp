// SPDX-License-Identifier: BSD-3-Clause
// The element matrices of either element kind (linear tetrahedra: stiffnessMatrix's
// elementMatrices; trilinear hexahedra: hexElements), for the couplings and checks that
// work element by element. Private to the library.
#pragma once

#include <Eigen/Core>
#include <asyncfem/volumetricMesh/tetMesh.hpp>

namespace asyncfem::detail {

/// Element-local DOFs of the mesh's elements: 12 (tetrahedra) or 24 (hexahedra), local
/// index 3 a + c for vertex a and coordinate c.
inline int elementDofs(const TetMesh& mesh) { return 3 * mesh.verticesPerElement(); }
/// The global DOF of element e's local DOF p.
inline int elementDof(const TetMesh& mesh, int e, int p) { return (3 * mesh.elementVertex(e, p / 3)) + (p % 3); }

/// The linear FEM stiffness of element e with its material (elementDofs() square).
Eigen::MatrixXd linearStiffnessOf(const TetMesh& mesh, int e);
/// The consistent or lumped mass of element e with its material's density.
Eigen::MatrixXd massOf(const TetMesh& mesh, int e, bool lumped);
/// The lumped mass of each vertex of element e (rho V / 4 per vertex of a tetrahedron,
/// rho int N_a dV per vertex of a hexahedron), verticesPerElement() entries.
Eigen::VectorXd vertexMassesOf(const TetMesh& mesh, int e);

}  // namespace asyncfem::detail
