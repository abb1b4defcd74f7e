// SPDX-License-Identifier: BSD-3-Clause
#include "detail/distributedSystem.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexElementMatrices.hpp>
#include <asyncfem/petscBackend/partition.hpp>
#include <climits>
#include <cmath>
#include <sstream>
#include <string>

#include "detail/petscCall.hpp"

namespace asyncfem::detail {

namespace {

using RowMajorElementMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Rest data of element e; ValidationError for a degenerate element, with the same
/// criterion as the single-process assembly (|V| <= 1e-14 L^3, L the longest edge).
ElementData elementData(const TetMesh& mesh, int e) {
  ElementData data;
  data.rest = mesh.elementRestPositions(e);
  data.gradients = shapeFunctionGradients(data.rest, &data.volume);
  double longestSquared = 0.0;
  for (int a = 0; a < 4; ++a) {
    for (int b = a + 1; b < 4; ++b) {
      longestSquared = std::max(longestSquared, (data.rest.col(a) - data.rest.col(b)).squaredNorm());
    }
  }
  const double longest = std::sqrt(longestSquared);
  if (!(std::abs(data.volume) > 1e-14 * longest * longest * longest) || !std::isfinite(data.volume)) {
    std::ostringstream message;
    message << "PETSc backend: element " << e << " is degenerate (signed volume " << data.volume << ", longest edge "
            << longest << ")";
    throw ValidationError(message.str());
  }
  data.density = mesh.elementMaterial(e).density;
  return data;
}

/// Rest data of hexahedron e: its volume (the sum of det J over the Gauss points) and
/// density; ValidationError naming the element and the Gauss point where det J <= 0.
ElementData hexElementData(const TetMesh& mesh, int e, HexElementPositions& rest) {
  rest = mesh.hexahedronRestPositions(e);
  HexGaussPoints points;
  try {
    points = hexGaussPoints(rest);
  } catch (const ValidationError& error) {
    throw ValidationError("PETSc backend: hexahedron " + std::to_string(e) + " has " + error.what());
  }
  ElementData data;
  for (const double volume : points.volumes) data.volume += volume;  // Gauss weights 1
  data.density = mesh.elementMaterial(e).density;
  return data;
}

}  // namespace

Eigen::MatrixXd DistributedSystem::elementMass(std::size_t k, MassType massType) const {
  const ElementData& data = elements[k];
  if (!hexRest.empty()) {
    return massType == MassType::lumped ? hexLumpedMass(hexRest[k], data.density)
                                        : hexConsistentMass(hexRest[k], data.density);
  }
  return massType == MassType::lumped ? lumpedElementMass(data.volume, data.density)
                                      : consistentElementMass(data.volume, data.density);
}

Eigen::MatrixXd DistributedSystem::elementStiffness(const TetMesh& mesh, std::size_t k) const {
  const Material& material = mesh.elementMaterial(layout.localElements[k]);
  if (!hexRest.empty()) return hexLinearStiffness(hexRest[k], material.youngsModulus, material.poissonRatio);
  return linearElementStiffness(elements[k].rest, material.youngsModulus, material.poissonRatio);
}

namespace {}  // namespace

DistributedSystem::DistributedSystem(MPI_Comm communicator, const TetMesh& mesh,
                                     const PetscSimulationSettings& settings)
    : comm(communicator), numDofs(mesh.numDofs()), nonlinear(settings.forceModel != PetscForceModelKind::linear) {
  partition(mesh, settings.fixedVertices);
  if (nonlinear) collectively(comm, [&] { forceModel = std::make_unique<LocalForceModel>(mesh, layout, settings); });
  createVectors();
  assembleMassAndStiffness(mesh, settings);
  assembleStaticForce(settings);
  attachNearNullSpace(mesh);
  checkPetsc(VecScatterCreateToZero(displacement.get(), toRoot.out(), rootVector.out()), "VecScatterCreateToZero");
}

// Partition on rank 0, broadcast (identical on every rank whatever METIS does); then the
// layout and the local elements' rest data.
void DistributedSystem::partition(const TetMesh& mesh, const std::vector<int>& fixedVertices) {
  int rank = 0;
  int numRanks = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &numRanks);
  const std::vector<int> parts = elementPartsOnEveryRank(mesh, comm);
  collectively(comm, [&] {
    layout = buildDistributedLayout(mesh, fixedVertices, parts, rank, numRanks);
    if (layout.numBlocks == 0) throw ValidationError("PETSc backend: every vertex is fixed, nothing to simulate");
    elements.reserve(layout.localElements.size());
    if (mesh.isHexahedral()) {
      hexRest.resize(layout.localElements.size());
      for (std::size_t k = 0; k < layout.localElements.size(); ++k)
        elements.push_back(hexElementData(mesh, layout.localElements[k], hexRest[k]));
    } else {
      for (int e : layout.localElements) elements.push_back(elementData(mesh, e));
    }
  });
}

void DistributedSystem::createVector(VecHandle& vector) const {
  checkPetsc(VecCreateMPI(comm, ownedDofs(), globalDofs(), vector.out()), "VecCreateMPI");
  checkPetsc(VecSetBlockSize(vector.get(), 3), "VecSetBlockSize");
  // Element scatters pass -1 for fixed DOFs, as MatSetValues accepts.
  checkPetsc(VecSetOption(vector.get(), VEC_IGNORE_NEGATIVE_INDICES, PETSC_TRUE), "VecSetOption");
}

void DistributedSystem::createMatrix(MatHandle& matrix) const {
  checkPetsc(MatCreate(comm, matrix.out()), "MatCreate");
  checkPetsc(MatSetSizes(matrix.get(), ownedDofs(), ownedDofs(), globalDofs(), globalDofs()), "MatSetSizes");
  checkPetsc(MatSetType(matrix.get(), MATAIJ), "MatSetType");
  checkPetsc(MatSetBlockSize(matrix.get(), 3), "MatSetBlockSize");
  checkPetsc(MatXAIJSetPreallocation(matrix.get(), 3, layout.diagonalBlocks.data(), layout.offDiagonalBlocks.data(),
                                     nullptr, nullptr),
             "MatXAIJSetPreallocation");
  // Re-assembly hits the same slots every time: let PETSc reuse the communication
  // pattern of the off-rank entries and refuse any entry outside the preallocation.
  checkPetsc(MatSetOption(matrix.get(), MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE), "MatSetOption");
  checkPetsc(MatSetOption(matrix.get(), MAT_SUBSET_OFF_PROC_ENTRIES, PETSC_TRUE), "MatSetOption");
}

/// Zeroes matrix (keeping its pattern) and adds every local element's matrix (12 x 12 or
/// 24 x 24).
template <class ElementFunction>
void DistributedSystem::assembleMatrix(Mat matrix, const ElementFunction& elementMatrix) {
  checkPetsc(MatZeroEntries(matrix), "MatZeroEntries");
  collectively(comm, [&] {
    RowMajorElementMatrix rowMajor;
    const PetscInt count = layout.dofsPerElement;
    for (std::size_t k = 0; k < elements.size(); ++k) {
      rowMajor = elementMatrix(k);
      const PetscInt* dofs = layout.elementDofs[k].data();
      checkPetsc(MatSetValues(matrix, count, dofs, count, dofs, rowMajor.data(), ADD_VALUES), "MatSetValues");
    }
  });
  checkPetsc(MatAssemblyBegin(matrix, MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
  checkPetsc(MatAssemblyEnd(matrix, MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
}

// M and K share the pattern; the system matrix is a value-wise combination of them. A
// nonlinear model's K is its tangent at rest (u = 0).
void DistributedSystem::assembleMassAndStiffness(const TetMesh& mesh, const PetscSimulationSettings& settings) {
  createMatrix(mass);
  createMatrix(stiffness);
  assembleMatrix(mass.get(), [&](std::size_t k) { return elementMass(k, settings.massType); });
  if (nonlinear) {
    checkPetsc(MatZeroEntries(stiffness.get()), "MatZeroEntries");
    assembleNonlinear(displacement.get(), stiffness.get());
  } else {
    assembleMatrix(stiffness.get(), [&](std::size_t k) { return elementStiffness(mesh, k); });
  }
  checkPetsc(MatDuplicate(mass.get(), MAT_COPY_VALUES, system.out()), "MatDuplicate");
  checkPetsc(MatSetOption(system.get(), MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE), "MatSetOption");
  if (nonlinear && settings.newton.maxIterations > 1) {
    checkPetsc(MatDuplicate(stiffness.get(), MAT_COPY_VALUES, iterateStiffness.out()), "MatDuplicate");
    checkPetsc(MatSetOption(iterateStiffness.get(), MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE), "MatSetOption");
  }
}

// The displacement (and a Newton iterate's) carries ghosts for the nonlinear element loop.
void DistributedSystem::createVectors() {
  checkPetsc(VecCreateGhost(comm, ownedDofs(), globalDofs(), static_cast<PetscInt>(layout.ghostDofs.size()),
                            layout.ghostDofs.data(), displacement.out()),
             "VecCreateGhost");
  for (VecHandle* vector : {&velocity, &acceleration, &staticForce, &externalForce, &internalForce, &rhs, &increment,
                            &work, &product, &residual, &correction, &candidate}) {
    createVector(*vector);
  }
  checkPetsc(VecSet(displacement.get(), 0.0), "VecSet");
  if (nonlinear) {
    checkPetsc(VecDuplicate(displacement.get(), trial.out()), "VecDuplicate");
    checkPetsc(VecSet(trial.get(), 0.0), "VecSet");
  }
  for (Vec vector : {velocity.get(), acceleration.get(), staticForce.get(), increment.get(), correction.get()}) {
    checkPetsc(VecSet(vector, 0.0), "VecSet");
  }
}

// Static external force: M g element by element (this includes the coupling of free and
// fixed DOFs, as the restriction of the full M * stacked g does) plus the owned entries
// of the constant force.
void DistributedSystem::assembleStaticForce(const PetscSimulationSettings& settings) {
  if (!settings.gravity.isZero(0.0)) {
    collectively(comm, [&] {
      Eigen::VectorXd stackedGravity(layout.dofsPerElement);
      for (int a = 0; 3 * a < layout.dofsPerElement; ++a) stackedGravity.segment<3>(3 * a) = settings.gravity;
      for (std::size_t k = 0; k < elements.size(); ++k) {
        const Eigen::VectorXd force = elementMass(k, settings.massType) * stackedGravity;
        checkPetsc(VecSetValues(staticForce.get(), layout.dofsPerElement, layout.elementDofs[k].data(), force.data(),
                                ADD_VALUES),
                   "VecSetValues");
      }
    });
  }
  checkPetsc(VecAssemblyBegin(staticForce.get()), "VecAssemblyBegin");
  checkPetsc(VecAssemblyEnd(staticForce.get()), "VecAssemblyEnd");
  if (settings.constantForce.size() != 0) {
    VecHandle constant;
    createVector(constant);
    scatterOwned(settings.constantForce, constant.get());
    checkPetsc(VecAXPY(staticForce.get(), 1.0, constant.get()), "VecAXPY");
  }
}

// Near null space for GAMG: the six rigid-body modes from the free vertices' rest
// positions (harmless for the other preconditioners, which ignore it).
void DistributedSystem::attachNearNullSpace(const TetMesh& mesh) {
  VecHandle coordinates;
  createVector(coordinates);
  PetscScalar* values = nullptr;
  checkPetsc(VecGetArray(coordinates.get(), &values), "VecGetArray");
  for (PetscInt row = 0; row < layout.ownedBlocks; ++row) {
    const int vertex = layout.blockVertex[static_cast<std::size_t>(layout.firstBlock + row)];
    for (int c = 0; c < 3; ++c) values[(3 * row) + c] = mesh.restPositions()(c, vertex);
  }
  checkPetsc(VecRestoreArray(coordinates.get(), &values), "VecRestoreArray");
  checkPetsc(MatNullSpaceCreateRigidBody(coordinates.get(), nearNullSpace.out()), "MatNullSpaceCreateRigidBody");
  checkPetsc(MatSetNearNullSpace(system.get(), nearNullSpace.get()), "MatSetNearNullSpace");
  checkPetsc(MatSetNearNullSpace(mass.get(), nearNullSpace.get()), "MatSetNearNullSpace");
}

void DistributedSystem::combineSystem(double massWeight, double stiffnessWeight, Mat extra, double extraWeight) {
  checkPetsc(MatCopy(mass.get(), system.get(), SAME_NONZERO_PATTERN), "MatCopy");
  checkPetsc(MatScale(system.get(), massWeight), "MatScale");
  checkPetsc(MatAXPY(system.get(), stiffnessWeight, stiffness.get(), SAME_NONZERO_PATTERN), "MatAXPY");
  if (extra != nullptr && extraWeight != 0.0) {
    checkPetsc(MatAXPY(system.get(), extraWeight, extra, SAME_NONZERO_PATTERN), "MatAXPY");
  }
}

namespace {

/// Runs use(values) on the local form (owned entries, then ghosts) of a ghosted vector,
/// after refreshing its ghosts.
template <class Use>
void withLocalForm(Vec ghosted, const Use& use) {
  checkPetsc(VecGhostUpdateBegin(ghosted, INSERT_VALUES, SCATTER_FORWARD), "VecGhostUpdateBegin");
  checkPetsc(VecGhostUpdateEnd(ghosted, INSERT_VALUES, SCATTER_FORWARD), "VecGhostUpdateEnd");
  Vec localForm = nullptr;
  checkPetsc(VecGhostGetLocalForm(ghosted, &localForm), "VecGhostGetLocalForm");
  const PetscScalar* values = nullptr;
  checkPetsc(VecGetArrayRead(localForm, &values), "VecGetArrayRead");
  use(values);
  checkPetsc(VecRestoreArrayRead(localForm, &values), "VecRestoreArrayRead");
  checkPetsc(VecGhostRestoreLocalForm(ghosted, &localForm), "VecGhostRestoreLocalForm");
}

}  // namespace

void DistributedSystem::assembleNonlinear(Vec ghostedDisplacement, Mat tangent) {
  if (tangent != nullptr) checkPetsc(MatZeroEntries(tangent), "MatZeroEntries");
  checkPetsc(VecSet(internalForce.get(), 0.0), "VecSet");
  withLocalForm(ghostedDisplacement, [&](const PetscScalar* values) {
    collectively(comm, [&] { forceModel->addForcesAndTangent(values, internalForce.get(), tangent); });
  });
  if (tangent != nullptr) checkPetsc(MatAssemblyBegin(tangent, MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
  checkPetsc(VecAssemblyBegin(internalForce.get()), "VecAssemblyBegin");
  if (tangent != nullptr) checkPetsc(MatAssemblyEnd(tangent, MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
  checkPetsc(VecAssemblyEnd(internalForce.get()), "VecAssemblyEnd");
}

double DistributedSystem::elasticEnergy(Vec ghostedDisplacement) {
  double local = 0.0;
  withLocalForm(ghostedDisplacement,
                [&](const PetscScalar* values) { collectively(comm, [&] { local = forceModel->energy(values); }); });
  double total = 0.0;
  MPI_Allreduce(&local, &total, 1, MPI_DOUBLE, MPI_SUM, comm);
  return total;
}

void DistributedSystem::scatterOwned(const Eigen::VectorXd& full, Vec vector) const {
  PetscScalar* values = nullptr;
  checkPetsc(VecGetArray(vector, &values), "VecGetArray");
  for (PetscInt row = 0; row < layout.ownedBlocks; ++row) {
    const auto vertex =
        static_cast<Eigen::Index>(layout.blockVertex[static_cast<std::size_t>(layout.firstBlock + row)]);
    for (int c = 0; c < 3; ++c) values[(3 * row) + c] = full[(3 * vertex) + c];
  }
  checkPetsc(VecRestoreArray(vector, &values), "VecRestoreArray");
}

void DistributedSystem::evaluateExternalForce(double t,
                                              const std::function<void(double, Eigen::VectorXd&)>& timeDependentForce) {
  checkPetsc(VecCopy(staticForce.get(), externalForce.get()), "VecCopy");
  if (!timeDependentForce) return;
  Eigen::VectorXd full;
  collectively(comm, [&] {
    full.setZero(numDofs);
    timeDependentForce(t, full);
    if (full.size() != numDofs) {
      throw ValidationError("PETSc backend: the time-dependent force returned " + std::to_string(full.size()) +
                            " values, expected " + std::to_string(numDofs));
    }
    for (Eigen::Index i = 0; i < full.size(); ++i) {
      if (!std::isfinite(full[i])) {
        throw NumericalError("PETSc backend: the time-dependent force is not finite at t = " + std::to_string(t) +
                             " (vertex " + std::to_string(i / 3) + ", coordinate " + std::to_string(i % 3) + ")");
      }
    }
  });
  VecHandle timeForce;
  createVector(timeForce);
  scatterOwned(full, timeForce.get());
  checkPetsc(VecAXPY(externalForce.get(), 1.0, timeForce.get()), "VecAXPY");
}

Eigen::VectorXd DistributedSystem::gather(Vec vector) const {
  checkPetsc(VecScatterBegin(toRoot.get(), vector, rootVector.get(), INSERT_VALUES, SCATTER_FORWARD),
             "VecScatterBegin");
  checkPetsc(VecScatterEnd(toRoot.get(), vector, rootVector.get(), INSERT_VALUES, SCATTER_FORWARD), "VecScatterEnd");
  if (layout.rank != 0) return {};
  Eigen::VectorXd full = Eigen::VectorXd::Zero(numDofs);
  const PetscScalar* values = nullptr;
  checkPetsc(VecGetArrayRead(rootVector.get(), &values), "VecGetArrayRead");
  for (PetscInt block = 0; block < layout.numBlocks; ++block) {
    const auto vertex = static_cast<Eigen::Index>(layout.blockVertex[static_cast<std::size_t>(block)]);
    for (int c = 0; c < 3; ++c) full[(3 * vertex) + c] = values[(3 * block) + c];
  }
  checkPetsc(VecRestoreArrayRead(rootVector.get(), &values), "VecRestoreArrayRead");
  return full;
}

int DistributedSystem::lowestNonFiniteVertex() const {
  int badVertex = INT_MAX;
  for (Vec vector : {displacement.get(), velocity.get()}) {
    const PetscScalar* values = nullptr;
    checkPetsc(VecGetArrayRead(vector, &values), "VecGetArrayRead");
    for (PetscInt i = 0; i < ownedDofs(); ++i) {
      if (!std::isfinite(values[i])) {
        badVertex = std::min(badVertex, layout.blockVertex[static_cast<std::size_t>(layout.firstBlock + (i / 3))]);
      }
    }
    checkPetsc(VecRestoreArrayRead(vector, &values), "VecRestoreArrayRead");
  }
  int globalBad = INT_MAX;
  MPI_Allreduce(&badVertex, &globalBad, 1, MPI_INT, MPI_MIN, comm);
  return globalBad == INT_MAX ? -1 : globalBad;
}

}  // namespace asyncfem::detail
