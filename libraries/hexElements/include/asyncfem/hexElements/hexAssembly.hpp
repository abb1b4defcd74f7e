// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/SparseCore>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>

namespace asyncfem {

/// Linear FEM stiffness K (3n x 3n, units of E times length) of a hexahedral mesh with its
/// per-element materials: the sum of hexLinearStiffness over the elements, assembled in
/// element order (deterministic). ValidationError on a tetrahedral mesh or an element with
/// det J <= 0 at a Gauss point (naming the element).
Eigen::SparseMatrix<double> hexLinearStiffnessMatrix(const TetMesh& mesh);

/// Mass matrix M (3n x 3n) of a hexahedral mesh, consistent or lumped (hexConsistentMass,
/// hexLumpedMass): 1_x^T M 1_x = sum_e rho_e V_e. Errors as hexLinearStiffnessMatrix.
Eigen::SparseMatrix<double> hexMassMatrix(const TetMesh& mesh, MassType type);

}  // namespace asyncfem
