// SPDX-License-Identifier: BSD-3-Clause
#include "detail/meshElements.hpp"

#include <asyncfem/hexElements/hexElementMatrices.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <cmath>

namespace asyncfem::detail {

Eigen::MatrixXd linearStiffnessOf(const TetMesh& mesh, int e) {
  const Material& material = mesh.elementMaterial(e);
  if (mesh.isHexahedral()) {
    return hexLinearStiffness(mesh.hexahedronRestPositions(e), material.youngsModulus, material.poissonRatio);
  }
  return linearElementStiffness(mesh.elementRestPositions(e), material.youngsModulus, material.poissonRatio);
}

Eigen::MatrixXd massOf(const TetMesh& mesh, int e, bool lumped) {
  const double density = mesh.elementMaterial(e).density;
  if (mesh.isHexahedral()) {
    const HexElementPositions rest = mesh.hexahedronRestPositions(e);
    return lumped ? hexLumpedMass(rest, density) : hexConsistentMass(rest, density);
  }
  double volume = 0.0;
  shapeFunctionGradients(mesh.elementRestPositions(e), &volume);
  return lumped ? lumpedElementMass(std::abs(volume), density) : consistentElementMass(std::abs(volume), density);
}

Eigen::VectorXd vertexMassesOf(const TetMesh& mesh, int e) {
  const double density = mesh.elementMaterial(e).density;
  if (mesh.isHexahedral()) {
    const Eigen::Matrix<double, 24, 24> lumped = hexLumpedMass(mesh.hexahedronRestPositions(e), density);
    Eigen::VectorXd out(8);
    for (int a = 0; a < 8; ++a) out[a] = lumped(3 * a, 3 * a);
    return out;
  }
  double volume = 0.0;
  shapeFunctionGradients(mesh.elementRestPositions(e), &volume);
  return Eigen::VectorXd::Constant(4, density * std::abs(volume) / 4.0);
}

}  // namespace asyncfem::detail
