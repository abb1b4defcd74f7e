// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/LU>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hyperelasticFEM/elementForceModel.hpp>
#include <cmath>
#include <sstream>
#include <string>
#include <utility>

namespace asyncfem {

namespace {

std::shared_ptr<const MatrixAssembler> checkedAssembler(const TetMesh& mesh,
                                                        std::shared_ptr<const MatrixAssembler> assembler,
                                                        const char* name) {
  if (!assembler) return std::make_shared<const MatrixAssembler>(mesh);
  if (assembler->numDofs() != mesh.numDofs() || assembler->numElements() != mesh.numElements()) {
    throw Error(std::string(name) + ": the assembler was built for a mesh with " +
                std::to_string(assembler->numDofs() / 3) + " vertices and " + std::to_string(assembler->numElements()) +
                " elements, not " + std::to_string(mesh.numVertices()) + " and " + std::to_string(mesh.numElements()));
  }
  return assembler;
}

}  // namespace

ElementForceModel::ElementForceModel(const TetMesh& mesh, std::shared_ptr<const MatrixAssembler> assembler,
                                     const char* name)
    : name_(name),
      geometry_(mesh, name),
      assembler_(checkedAssembler(mesh, std::move(assembler), name)),
      elementForces_(static_cast<std::size_t>(mesh.numElements()), ElementVector::Zero()),
      elementEnergies_(static_cast<std::size_t>(mesh.numElements()), 0.0) {}

Eigen::SparseMatrix<double> ElementForceModel::createStiffnessMatrix() const { return assembler_->createMatrix(); }

void ElementForceModel::checkDisplacement(const Eigen::VectorXd& displacement, const char* caller) const {
  if (displacement.size() != geometry_.numDofs) {
    throw Error(name_ + "::" + caller + ": displacement has size " + std::to_string(displacement.size()) +
                ", expected " + std::to_string(geometry_.numDofs));
  }
}

void ElementForceModel::ensurePattern(Eigen::SparseMatrix<double>& stiffness) const {
  if (stiffness.rows() != geometry_.numDofs || stiffness.cols() != geometry_.numDofs || !stiffness.isCompressed() ||
      stiffness.nonZeros() != assembler_->nonZeros()) {
    stiffness = assembler_->createMatrix();
  }
}

void ElementForceModel::reportNonFinite(int element, const Eigen::VectorXd& displacement, const char* what) const {
  std::ostringstream message;
  message << name_ << ": element " << element << " has a non-finite " << what
          << " (J = det F = " << geometry_.deformationGradient(element, displacement).determinant()
          << "); enable inversion handling (an inversion threshold in (0, 1)) or reduce the step";
  throw NumericalError(message.str());
}

void ElementForceModel::evaluate(const Eigen::VectorXd& displacement, Eigen::VectorXd* forces,
                                 Eigen::SparseMatrix<double>* stiffness, const char* caller) {
  checkDisplacement(displacement, caller);
  const int count = numElements();
  if (stiffness != nullptr) {
    ensurePattern(*stiffness);
    // One reference capture keeps the std::function in its small buffer (no allocation).
    struct Context {
      ElementForceModel* model;
      const Eigen::VectorXd* displacement;
      bool wantForces;
    } context{this, &displacement, forces != nullptr};
    assembler_->assembleBatches(
        [&context](int first, int count, ElementMatrix* out) {
          ElementForceModel& model = *context.model;
          std::array<Eigen::Matrix3d, MatrixAssembler::kElementBatch> f;
          for (int i = 0; i < count; ++i) {
            f[static_cast<std::size_t>(i)] = model.geometry_.deformationGradient(first + i, *context.displacement);
          }
          ElementVector* force = context.wantForces ? &model.elementForces_[static_cast<std::size_t>(first)] : nullptr;
          model.computeBatch(first, count, f.data(), force, out);
          for (int i = 0; i < count; ++i) {
            if (!out[i].allFinite()) model.reportNonFinite(first + i, *context.displacement, "tangent");
          }
        },
        *stiffness);
  } else if (forces != nullptr) {
#pragma omp parallel for schedule(static)
    for (int e = 0; e < count; ++e) {
      computeElement(e, geometry_.deformationGradient(e, displacement), nullptr,
                     &elementForces_[static_cast<std::size_t>(e)], nullptr);
    }
  }
  if (forces == nullptr) return;
  if (forces->size() != geometry_.numDofs) forces->resize(geometry_.numDofs);
  forces->setZero();
  // Serial scatter in element order: the sums do not depend on the thread count.
  for (int e = 0; e < count; ++e) {
    const ElementVector& local = elementForces_[static_cast<std::size_t>(e)];
    if (!local.allFinite()) reportNonFinite(e, displacement, "force");
    for (int a = 0; a < 4; ++a) {
      forces->segment<3>(3 * static_cast<Eigen::Index>(geometry_.elements(a, e))) += local.segment<3>(3 * a);
    }
  }
}

void ElementForceModel::computeBatch(int first, int count, const Eigen::Matrix3d* deformationGradients,
                                     ElementVector* forces, ElementMatrix* tangents) const {
  for (int i = 0; i < count; ++i) {
    computeElement(first + i, deformationGradients[i], nullptr, forces != nullptr ? forces + i : nullptr, tangents + i);
  }
}

void ElementForceModel::internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) {
  evaluate(displacement, &forces, nullptr, "internalForces");
}

void ElementForceModel::tangentStiffness(const Eigen::VectorXd& displacement, Eigen::SparseMatrix<double>& stiffness) {
  evaluate(displacement, nullptr, &stiffness, "tangentStiffness");
}

void ElementForceModel::forcesAndTangent(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces,
                                         Eigen::SparseMatrix<double>& stiffness) {
  evaluate(displacement, &forces, &stiffness, "forcesAndTangent");
}

double ElementForceModel::elasticEnergy(const Eigen::VectorXd& displacement) {
  checkDisplacement(displacement, "elasticEnergy");
  const int count = numElements();
#pragma omp parallel for schedule(static)
  for (int e = 0; e < count; ++e) {
    computeElement(e, geometry_.deformationGradient(e, displacement), &elementEnergies_[static_cast<std::size_t>(e)],
                   nullptr, nullptr);
  }
  double energy = 0.0;
  for (int e = 0; e < count; ++e) {
    const double value = elementEnergies_[static_cast<std::size_t>(e)];
    if (!std::isfinite(value)) reportNonFinite(e, displacement, "energy");
    energy += value;
  }
  return energy;
}

void ElementForceModel::elementTerms(const Eigen::VectorXd& displacement, int element, double* energy,
                                     ElementVector* force, ElementMatrix* tangent) const {
  checkDisplacement(displacement, "elementTerms");
  if (element < 0 || element >= numElements()) {
    throw Error(name_ + ": element " + std::to_string(element) + " is out of range [0, " +
                std::to_string(numElements()) + ")");
  }
  computeElement(element, geometry_.deformationGradient(element, displacement), energy, force, tangent);
}

bool ElementForceModel::elementTangent(const Eigen::VectorXd& displacement, int element, ElementMatrix& tangent) const {
  elementTerms(displacement, element, nullptr, nullptr, &tangent);
  return true;
}

}  // namespace asyncfem
