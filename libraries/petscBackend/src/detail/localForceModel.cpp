// SPDX-License-Identifier: BSD-3-Clause
#include "detail/localForceModel.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/hyperelasticFEM/factory.hpp>
#include <regex>
#include <string>

#include "detail/petscCall.hpp"

namespace asyncfem::detail {

namespace {

/// The sub-mesh of the elements elements (ascending mesh ids): their vertices in
/// ascending mesh id (meshVertex), the materials as they are.
TetMesh subMesh(const TetMesh& mesh, const std::vector<int>& elements, std::vector<int>& meshVertex) {
  meshVertex.clear();
  for (int e : elements) {
    for (int a = 0; a < 4; ++a) meshVertex.push_back(mesh.elements()(a, e));
  }
  std::sort(meshVertex.begin(), meshVertex.end());
  meshVertex.erase(std::unique(meshVertex.begin(), meshVertex.end()), meshVertex.end());
  std::vector<int> subVertex(static_cast<std::size_t>(mesh.numVertices()), -1);
  Eigen::Matrix3Xd positions(3, static_cast<Eigen::Index>(meshVertex.size()));
  for (std::size_t i = 0; i < meshVertex.size(); ++i) {
    subVertex[static_cast<std::size_t>(meshVertex[i])] = static_cast<int>(i);
    positions.col(static_cast<Eigen::Index>(i)) = mesh.restPositions().col(meshVertex[i]);
  }
  Eigen::Matrix4Xi connectivity(4, static_cast<Eigen::Index>(elements.size()));
  std::vector<int> materials;
  materials.reserve(elements.size());
  for (std::size_t k = 0; k < elements.size(); ++k) {
    for (int a = 0; a < 4; ++a) {
      connectivity(a, static_cast<Eigen::Index>(k)) =
          subVertex[static_cast<std::size_t>(mesh.elements()(a, elements[k]))];
    }
    materials.push_back(mesh.elementMaterialIndex(elements[k]));
  }
  return TetMesh(std::move(positions), std::move(connectivity), mesh.materials(), std::move(materials));
}

std::unique_ptr<ForceModel> makeModel(const TetMesh& mesh, const PetscSimulationSettings& settings) {
  switch (settings.forceModel) {
    case PetscForceModelKind::corotational:
      return std::make_unique<CorotationalLinearFEM>(mesh, settings.tangent);
    case PetscForceModelKind::stvk:
      return makeHyperelasticForceModel(mesh, HyperelasticMaterialKind::stvk, settings.hyperelastic);
    case PetscForceModelKind::neoHookean:
      return makeHyperelasticForceModel(mesh, HyperelasticMaterialKind::neoHookean, settings.hyperelastic);
    case PetscForceModelKind::mooneyRivlin:
      return makeHyperelasticForceModel(mesh, HyperelasticMaterialKind::mooneyRivlin, settings.hyperelastic);
    case PetscForceModelKind::linear:
      break;
  }
  throw Error("PETSc backend: the linear model has no local force model");
}

/// Runs work; an asyncfem error it throws is thrown again with the same type and every
/// "element N" of its message (a sub-mesh element) replaced by the mesh's element id.
template <class Work>
void inMeshNumbering(const std::vector<int>& meshElement, const Work& work) {
  const auto translate = [&](const std::string& message) {
    static const std::regex elementNumber("element (\\d+)");
    std::string result;
    auto last = message.cbegin();
    for (std::sregex_iterator it(message.begin(), message.end(), elementNumber), end; it != end; ++it) {
      const std::size_t sub = std::stoul((*it)[1].str());
      result.append(last, message.cbegin() + it->position());
      result += "element " + (sub < meshElement.size() ? std::to_string(meshElement[sub]) : (*it)[1].str());
      last = message.cbegin() + it->position() + it->length();
    }
    result.append(last, message.cend());
    return result;
  };
  try {
    work();
  } catch (const NumericalError& error) {
    throw NumericalError(translate(error.what()));
  } catch (const ValidationError& error) {
    throw ValidationError(translate(error.what()));
  } catch (const Error& error) {
    throw Error(translate(error.what()));
  }
}

}  // namespace

LocalForceModel::LocalForceModel(const TetMesh& mesh, const DistributedLayout& layout,
                                 const PetscSimulationSettings& settings)
    : meshElement_(layout.localElements) {
  std::vector<int> meshVertex;
  const TetMesh part = subMesh(mesh, meshElement_, meshVertex);
  // Each element's DOF indices name its vertices' indices; the sub-mesh vertex of corner
  // a of local element k is part.elements()(a, k).
  localFormDof_.assign(static_cast<std::size_t>(part.numDofs()), -1);
  globalDof_.assign(static_cast<std::size_t>(part.numDofs()), -1);
  for (std::size_t k = 0; k < meshElement_.size(); ++k) {
    for (int i = 0; i < 12; ++i) {
      const auto dof = static_cast<std::size_t>((3 * part.elements()(i / 3, static_cast<Eigen::Index>(k))) + (i % 3));
      localFormDof_[dof] = layout.elementLocalDofs[k][static_cast<std::size_t>(i)];
      globalDof_[dof] = layout.elementDofs[k][static_cast<std::size_t>(i)];
    }
  }
  inMeshNumbering(meshElement_, [&] { model_ = makeModel(part, settings); });
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
