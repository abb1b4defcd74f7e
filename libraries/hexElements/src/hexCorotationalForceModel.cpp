// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexCorotational.hpp>
#include <asyncfem/hexElements/hexCorotationalForceModel.hpp>
#include <string>

namespace asyncfem {

HexCorotationalForceModel::HexCorotationalForceModel(const TetMesh& mesh, bool simpleTangent)
    : HexForceModel(mesh, "HexCorotationalForceModel"), simpleTangent_(simpleTangent) {
  const int numElements = mesh.numElements();
  stiffness_.reserve(static_cast<std::size_t>(numElements));
  centreGradients_.reserve(static_cast<std::size_t>(numElements));
  for (int e = 0; e < numElements; ++e) {
    const Material& material = mesh.elementMaterial(e);
    const HexElementPositions rest = mesh.hexahedronRestPositions(e);
    try {  // the rest shape: det J > 0 at every Gauss point
      stiffness_.push_back(hexLinearStiffness(rest, material.youngsModulus, material.poissonRatio));
    } catch (const ValidationError& error) {
      throw ValidationError("HexCorotationalForceModel: element " + std::to_string(e) + ": " + error.what());
    }
    centreGradients_.push_back(hexShapeGradients(rest, Eigen::Vector3d::Zero(), nullptr));
  }
}

HexElementEnergy HexCorotationalForceModel::element(Eigen::Index e, const HexElementPositions& rest,
                                                    const HexElementPositions& deformed, bool withTangent) const {
  const auto i = static_cast<std::size_t>(e);
  return hexCorotational(rest, centreGradients_[i], stiffness_[i], deformed, simpleTangent_, withTangent);
}

}  // namespace asyncfem
