// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexStvk.hpp>
#include <asyncfem/hexElements/hexStvkForceModel.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <string>

namespace asyncfem {

HexStvkForceModel::HexStvkForceModel(const TetMesh& mesh) : HexForceModel(mesh, "HexStvkForceModel") {
  const int numElements = mesh.numElements();
  lame_.reserve(static_cast<std::size_t>(numElements));
  gaussPoints_.reserve(static_cast<std::size_t>(numElements));
  for (int e = 0; e < numElements; ++e) {
    const Material& material = mesh.elementMaterial(e);
    lame_.push_back(lameParameters(material.youngsModulus, material.poissonRatio));
    try {  // the rest shape: det J > 0 at every Gauss point, as the linear stiffness checks
      gaussPoints_.push_back(hexGaussPoints(mesh.hexahedronRestPositions(e)));
    } catch (const ValidationError& error) {
      throw ValidationError("HexStvkForceModel: element " + std::to_string(e) + ": " + error.what());
    }
  }
}

HexElementEnergy HexStvkForceModel::element(Eigen::Index e, const HexElementPositions& /*rest*/,
                                            const HexElementPositions& deformed, bool withTangent) const {
  const auto i = static_cast<std::size_t>(e);
  return hexStvk(gaussPoints_[i], deformed, lame_[i], withTangent);
}

}  // namespace asyncfem
