// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexAssembly.hpp>
#include <asyncfem/hexElements/hexElementMatrices.hpp>
#include <string>
#include <vector>

namespace asyncfem {

namespace {

/// Sums elementMatrix(e) (24 x 24) over the hexahedra into a 3n x 3n matrix; errors from
/// an element are rethrown naming it.
template <class ElementMatrixFunction>
Eigen::SparseMatrix<double> assembleHexahedra(const TetMesh& mesh, const char* what,
                                              const ElementMatrixFunction& elementMatrix) {
  const HexElements& hexahedra = mesh.hexahedra();
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<std::size_t>(mesh.numElements()) * 24 * 24);
  for (int e = 0; e < mesh.numElements(); ++e) {
    HexElementMatrix local;
    try {
      local = elementMatrix(e);
    } catch (const ValidationError& error) {
      throw ValidationError(std::string(what) + ": element " + std::to_string(e) + ": " + error.what());
    }
    for (int a = 0; a < 8; ++a)
      for (int b = 0; b < 8; ++b)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) {
            const double value = local((3 * a) + i, (3 * b) + j);
            if (value != 0.0) entries.emplace_back((3 * hexahedra(a, e)) + i, (3 * hexahedra(b, e)) + j, value);
          }
  }
  Eigen::SparseMatrix<double> matrix(mesh.numDofs(), mesh.numDofs());
  matrix.setFromTriplets(entries.begin(), entries.end());
  return matrix;
}

}  // namespace

Eigen::SparseMatrix<double> hexLinearStiffnessMatrix(const TetMesh& mesh) {
  return assembleHexahedra(mesh, "hexLinearStiffnessMatrix", [&](int e) {
    const Material& material = mesh.elementMaterial(e);
    return hexLinearStiffness(mesh.hexahedronRestPositions(e), material.youngsModulus, material.poissonRatio);
  });
}

Eigen::SparseMatrix<double> hexMassMatrix(const TetMesh& mesh, MassType type) {
  return assembleHexahedra(mesh, "hexMassMatrix", [&](int e) {
    const double density = mesh.elementMaterial(e).density;
    return type == MassType::lumped ? hexLumpedMass(mesh.hexahedronRestPositions(e), density)
                                    : hexConsistentMass(mesh.hexahedronRestPositions(e), density);
  });
}

}  // namespace asyncfem
