// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <petscmat.h>
#include <petscvec.h>

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/forceModel/forceModel.hpp>
#include <asyncfem/petscBackend/petscSimulation.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <memory>
#include <vector>

#include "detail/distributedLayout.hpp"

namespace asyncfem::detail {

/// This rank's share of a nonlinear force model: the single-process force model of the
/// settings (CorotationalLinearFEM, or the hyperelastic model makeHyperelasticForceModel
/// builds) on the sub-mesh of the rank's elements, so every element goes through the same
/// kernel as in a one-process run. Its forces and tangent (3m, 3m x 3m on the m vertices
/// of the sub-mesh) are added into the distributed vector and matrix through the global
/// DOF numbering (fixed DOFs as -1, which PETSc skips); entries of vertices shared with
/// other ranks hold this rank's elements only, and PETSc's assembly sums them.
class LocalForceModel {
 public:
  /// mesh: the whole (replicated) mesh; layout: this rank's elements and numbering.
  /// Throws what the force model's constructor throws, with sub-mesh element numbers
  /// translated to the mesh's.
  LocalForceModel(const TetMesh& mesh, const DistributedLayout& layout, const PetscSimulationSettings& settings);

  /// Adds this rank's f_int(u) into forces and K(u) into tangent (each may be null;
  /// no assembly calls). localForm: the local form of the ghosted displacement. A
  /// failure of the model (a non-finite element) throws with the mesh's element number.
  void addForcesAndTangent(const PetscScalar* localForm, Vec forces, Mat tangent);
  /// The elastic energy of this rank's elements at the displacement (not summed over ranks).
  double energy(const PetscScalar* localForm);

 private:
  void gatherDisplacement(const PetscScalar* localForm);

  std::vector<int> meshElement_;         // sub-mesh element -> mesh element
  std::vector<PetscInt> localFormDof_;   // 3m: index in the ghosted local form, -1 fixed
  std::vector<PetscInt> globalDof_;      // 3m: global row, -1 fixed
  std::vector<PetscInt> globalColumns_;  // per stored entry of tangent_: its global column
  std::unique_ptr<ForceModel> model_;
  Eigen::VectorXd displacement_, forces_;
  Eigen::SparseMatrix<double> tangent_;
};

}  // namespace asyncfem::detail
