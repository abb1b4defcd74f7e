// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexStvk.hpp>
#include <asyncfem/hexElements/hexStvkForceModel.hpp>
#include <string>

namespace asyncfem {

HexStvkForceModel::HexStvkForceModel(const TetMesh& mesh) : HexForceModel(mesh, "HexStvkForceModel") {
  const int numElements = mesh.numElements();
  youngAndPoisson_.reserve(static_cast<std::size_t>(numElements));
  for (int e = 0; e < numElements; ++e) {
    const Material& material = mesh.elementMaterial(e);
    youngAndPoisson_.emplace_back(material.youngsModulus, material.poissonRatio);
    try {  // the rest shape: det J > 0 at every Gauss point, as the linear stiffness checks
      (void)hexStvk(mesh.hexahedronRestPositions(e), mesh.hexahedronRestPositions(e), material.youngsModulus,
                    material.poissonRatio, false);
    } catch (const ValidationError& error) {
      throw ValidationError("HexStvkForceModel: element " + std::to_string(e) + ": " + error.what());
    }
  }
}

HexElementEnergy HexStvkForceModel::element(Eigen::Index e, const HexElementPositions& rest,
                                            const HexElementPositions& deformed, bool withTangent) const {
  const Eigen::Vector2d& material = youngAndPoisson_[static_cast<std::size_t>(e)];
  return hexStvk(rest, deformed, material[0], material[1], withTangent);
}

}  // namespace asyncfem
