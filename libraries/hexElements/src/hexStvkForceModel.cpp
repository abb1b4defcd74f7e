// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexStvk.hpp>
#include <asyncfem/hexElements/hexStvkForceModel.hpp>
#include <string>

namespace asyncfem {

HexStvkForceModel::HexStvkForceModel(const TetMesh& mesh)
    : numDofs_(mesh.numDofs()), restPositions_(mesh.restPositions()), hexahedra_(mesh.hexahedra()) {
  const int numElements = mesh.numElements();
  youngAndPoisson_.reserve(static_cast<std::size_t>(numElements));
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<std::size_t>(numElements) * 64 * 9);
  for (int e = 0; e < numElements; ++e) {
    const Material& material = mesh.elementMaterial(e);
    youngAndPoisson_.emplace_back(material.youngsModulus, material.poissonRatio);
    try {  // the rest shape: det J > 0 at every Gauss point, as the linear stiffness checks
      (void)hexStvk(mesh.hexahedronRestPositions(e), mesh.hexahedronRestPositions(e), material.youngsModulus,
                    material.poissonRatio, false);
    } catch (const ValidationError& error) {
      throw ValidationError("HexStvkForceModel: element " + std::to_string(e) + ": " + error.what());
    }
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

void HexStvkForceModel::checkDisplacement(const Eigen::VectorXd& displacement, const char* what) const {
  if (displacement.size() != numDofs_) {
    throw Error(std::string("HexStvkForceModel::") + what + ": displacement has " +
                std::to_string(displacement.size()) + " entries, expected " + std::to_string(numDofs_));
  }
}

double HexStvkForceModel::evaluate(const Eigen::VectorXd& displacement, Eigen::VectorXd* forces,
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
    const Eigen::Vector2d& material = youngAndPoisson_[static_cast<std::size_t>(e)];
    const HexStvkElement element = hexStvk(rest, deformed, material[0], material[1], stiffness != nullptr);
    energy += element.energy;
    if (forces != nullptr) {
      for (int a = 0; a < 8; ++a)
        forces->segment<3>(3 * static_cast<Eigen::Index>(hexahedra_(a, e))) += element.force.segment<3>(3 * a);
    }
    if (stiffness != nullptr) {
      double* values = stiffness->valuePtr();
      const Eigen::Matrix<int, 8, 8>& slots = blockSlots_[static_cast<std::size_t>(e)];
      for (int b = 0; b < 8; ++b) {
        const int length = columnLength_[static_cast<std::size_t>(hexahedra_(b, e))];
        for (int a = 0; a < 8; ++a)
          for (int j = 0; j < 3; ++j)
            for (int i = 0; i < 3; ++i)
              values[slots(a, b) + (j * length) + i] += element.tangent((3 * a) + i, (3 * b) + j);
      }
    }
  }
  return energy;
}

void HexStvkForceModel::internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) {
  checkDisplacement(displacement, "internalForces");
  evaluate(displacement, &forces, nullptr);
}

void HexStvkForceModel::tangentStiffness(const Eigen::VectorXd& displacement, Eigen::SparseMatrix<double>& stiffness) {
  checkDisplacement(displacement, "tangentStiffness");
  evaluate(displacement, nullptr, &stiffness);
}

void HexStvkForceModel::forcesAndTangent(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces,
                                         Eigen::SparseMatrix<double>& stiffness) {
  checkDisplacement(displacement, "forcesAndTangent");
  evaluate(displacement, &forces, &stiffness);
}

double HexStvkForceModel::elasticEnergy(const Eigen::VectorXd& displacement) {
  checkDisplacement(displacement, "elasticEnergy");
  return evaluate(displacement, nullptr, nullptr);
}

}  // namespace asyncfem
