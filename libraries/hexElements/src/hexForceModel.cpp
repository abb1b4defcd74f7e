// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexForceModel.hpp>
#include <string>
#include <utility>

namespace asyncfem {

HexForceModel::HexForceModel(const TetMesh& mesh, std::string name)
    : name_(std::move(name)),
      numDofs_(mesh.numDofs()),
      restPositions_(mesh.restPositions()),
      hexahedra_(mesh.hexahedra()) {
  const int numElements = mesh.numElements();
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<std::size_t>(numElements) * 64 * 9);
  for (int e = 0; e < numElements; ++e) {
    for (int a = 0; a < 8; ++a)
      for (int b = 0; b < 8; ++b)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) entries.emplace_back((3 * hexahedra_(a, e)) + i, (3 * hexahedra_(b, e)) + j, 0.0);
  }
  pattern_.resize(numDofs_, numDofs_);
  pattern_.setFromTriplets(entries.begin(), entries.end());
  pattern_.makeCompressed();
  const int* outer = pattern_.outerIndexPtr();
  const int* inner = pattern_.innerIndexPtr();
  columnLength_.resize(static_cast<std::size_t>(mesh.numVertices()));
  for (int v = 0; v < mesh.numVertices(); ++v)
    columnLength_[static_cast<std::size_t>(v)] = outer[(3 * v) + 1] - outer[3 * v];
  blockSlots_.resize(static_cast<std::size_t>(numElements));
  for (int e = 0; e < numElements; ++e) {
    for (int b = 0; b < 8; ++b) {
      const int column = 3 * hexahedra_(b, e);
      for (int a = 0; a < 8; ++a) {
        const int* found = std::lower_bound(inner + outer[column], inner + outer[column + 1], 3 * hexahedra_(a, e));
        blockSlots_[static_cast<std::size_t>(e)](a, b) = static_cast<int>(found - inner);
      }
    }
  }
}

void HexForceModel::checkDisplacement(const Eigen::VectorXd& displacement, const char* what) const {
  if (displacement.size() != numDofs_) {
    throw Error(name_ + "::" + what + ": displacement has " + std::to_string(displacement.size()) +
                " entries, expected " + std::to_string(numDofs_));
  }
}

double HexForceModel::evaluate(const Eigen::VectorXd& displacement, Eigen::VectorXd* forces,
                               Eigen::SparseMatrix<double>* stiffness) const {
  if (forces != nullptr) forces->setZero(numDofs_);
  if (stiffness != nullptr) {
    if (stiffness->nonZeros() != pattern_.nonZeros() || !stiffness->isCompressed()) *stiffness = pattern_;
    std::fill(stiffness->valuePtr(), stiffness->valuePtr() + stiffness->nonZeros(), 0.0);
  }
  double energy = 0.0;
  for (Eigen::Index e = 0; e < hexahedra_.cols(); ++e) {
    HexElementPositions rest;
    HexElementPositions deformed;
    for (int a = 0; a < 8; ++a) {
      const int v = hexahedra_(a, e);
      rest.col(a) = restPositions_.col(v);
      deformed.col(a) = rest.col(a) + displacement.segment<3>(3 * static_cast<Eigen::Index>(v));
    }
    const HexElementEnergy result = element(e, rest, deformed, stiffness != nullptr);
    energy += result.energy;
    if (forces != nullptr) {
      for (int a = 0; a < 8; ++a)
        forces->segment<3>(3 * static_cast<Eigen::Index>(hexahedra_(a, e))) += result.force.segment<3>(3 * a);
    }
    if (stiffness != nullptr) {
      double* values = stiffness->valuePtr();
      const Eigen::Matrix<int, 8, 8>& slots = blockSlots_[static_cast<std::size_t>(e)];
      for (int b = 0; b < 8; ++b) {
        const int length = columnLength_[static_cast<std::size_t>(hexahedra_(b, e))];
        for (int a = 0; a < 8; ++a)
          for (int j = 0; j < 3; ++j)
            for (int i = 0; i < 3; ++i)
              values[slots(a, b) + (j * length) + i] += result.tangent((3 * a) + i, (3 * b) + j);
      }
    }
  }
  return energy;
}

void HexForceModel::internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) {
  checkDisplacement(displacement, "internalForces");
  evaluate(displacement, &forces, nullptr);
}

void HexForceModel::tangentStiffness(const Eigen::VectorXd& displacement, Eigen::SparseMatrix<double>& stiffness) {
  checkDisplacement(displacement, "tangentStiffness");
  evaluate(displacement, nullptr, &stiffness);
}

void HexForceModel::forcesAndTangent(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces,
                                     Eigen::SparseMatrix<double>& stiffness) {
  checkDisplacement(displacement, "forcesAndTangent");
  evaluate(displacement, &forces, &stiffness);
}

double HexForceModel::elasticEnergy(const Eigen::VectorXd& displacement) {
  checkDisplacement(displacement, "elasticEnergy");
  return evaluate(displacement, nullptr, nullptr);
}

}  // namespace asyncfem
