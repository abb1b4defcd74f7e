// SPDX-License-Identifier: BSD-3-Clause
#include "detail/localForceModel.hpp"

#include "detail/petscCall.hpp"
#include "detail/subMeshModel.hpp"

namespace asyncfem::detail {

LocalForceModel::LocalForceModel(const TetMesh& mesh, const DistributedLayout& layout,
                                 const PetscSimulationSettings& settings)
    : meshElement_(layout.localElements) {
  std::vector<int> meshVertex;
  const TetMesh part = subMesh(mesh, meshElement_, meshVertex);
  // Each element's DOF indices name its vertices' indices; the sub-mesh vertex of corner
  // a of local element k is part.elementVertex(k, a).
  localFormDof_.assign(static_cast<std::size_t>(part.numDofs()), -1);
  globalDof_.assign(static_cast<std::size_t>(part.numDofs()), -1);
  for (std::size_t k = 0; k < meshElement_.size(); ++k) {
    for (int i = 0; i < layout.dofsPerElement; ++i) {
      const auto dof = static_cast<std::size_t>((3 * part.elementVertex(static_cast<int>(k), i / 3)) + (i % 3));
      localFormDof_[dof] = layout.elementLocalDofs[k][static_cast<std::size_t>(i)];
      globalDof_[dof] = layout.elementDofs[k][static_cast<std::size_t>(i)];
    }
  }
  inMeshNumbering(meshElement_, [&] {
    model_ = makeSubMeshModel(part, settings.forceModel, settings.tangent, settings.hyperelastic);
  });
  tangent_ = model_->createStiffnessMatrix();
  globalColumns_.resize(static_cast<std::size_t>(tangent_.nonZeros()));
  for (Eigen::Index p = 0; p < tangent_.nonZeros(); ++p) {
    globalColumns_[static_cast<std::size_t>(p)] = globalDof_[static_cast<std::size_t>(tangent_.innerIndexPtr()[p])];
  }
  displacement_.setZero(part.numDofs());
}

void LocalForceModel::gatherDisplacement(const PetscScalar* localForm) {
  for (std::size_t i = 0; i < localFormDof_.size(); ++i) {
    const PetscInt local = localFormDof_[i];
    displacement_[static_cast<Eigen::Index>(i)] = local >= 0 ? localForm[local] : 0.0;
  }
}

void LocalForceModel::addForcesAndTangent(const PetscScalar* localForm, Vec forces, Mat tangent) {
  gatherDisplacement(localForm);
  inMeshNumbering(meshElement_, [&] {
    if (tangent != nullptr && forces != nullptr) {
      model_->forcesAndTangent(displacement_, forces_, tangent_);
    } else if (tangent != nullptr) {
      model_->tangentStiffness(displacement_, tangent_);
    } else {
      model_->internalForces(displacement_, forces_);
    }
  });
  if (forces != nullptr) {
    checkPetsc(
        VecSetValues(forces, static_cast<PetscInt>(forces_.size()), globalDof_.data(), forces_.data(), ADD_VALUES),
        "VecSetValues");
  }
  if (tangent == nullptr) return;
  // Column j of the (symmetric, fully stored) tangent is its row j.
  for (Eigen::Index j = 0; j < tangent_.outerSize(); ++j) {
    const PetscInt row = globalDof_[static_cast<std::size_t>(j)];
    if (row < 0) continue;
    const Eigen::Index begin = tangent_.outerIndexPtr()[j];
    const auto count = static_cast<PetscInt>(tangent_.outerIndexPtr()[j + 1] - begin);
    checkPetsc(
        MatSetValues(tangent, 1, &row, count, globalColumns_.data() + begin, tangent_.valuePtr() + begin, ADD_VALUES),
        "MatSetValues");
  }
}

double LocalForceModel::energy(const PetscScalar* localForm) {
  gatherDisplacement(localForm);
  double result = 0.0;
  inMeshNumbering(meshElement_, [&] { result = model_->elasticEnergy(displacement_); });
  return result;
}

}  // namespace asyncfem::detail
