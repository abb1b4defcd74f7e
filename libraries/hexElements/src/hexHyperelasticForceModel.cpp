// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/LU>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexHyperelasticForceModel.hpp>
#include <asyncfem/hexElements/hexStvkForceModel.hpp>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace asyncfem {

HexHyperelasticForceModel::HexHyperelasticForceModel(const TetMesh& mesh, HyperelasticMaterialKind kind,
                                                     const HyperelasticOptions& options)
    : HexForceModel(mesh, "HexHyperelasticForceModel"),
      kind_(kind),
      options_(options),
      materials_(mesh.materials().size()),
      elementMaterials_(mesh.elementMaterials()) {
  const int numElements = mesh.numElements();
  gaussPoints_.reserve(static_cast<std::size_t>(numElements));
  for (int e = 0; e < numElements; ++e) {
    const auto m = static_cast<std::size_t>(elementMaterials_[static_cast<std::size_t>(e)]);
    try {
      if (!materials_[m]) materials_[m].emplace(kind_, mesh.materials()[m], options_);
      gaussPoints_.push_back(hexGaussPoints(mesh.hexahedronRestPositions(e)));
    } catch (const ValidationError& error) {
      throw ValidationError(name() + ": element " + std::to_string(e) + ": " + error.what());
    }
  }
}

HexElementEnergy HexHyperelasticForceModel::element(Eigen::Index e, const HexElementPositions& /*rest*/,
                                                    const HexElementPositions& deformed, bool withTangent) const {
  const auto i = static_cast<std::size_t>(e);
  const IsotropicMaterialPoint& material = *materials_[static_cast<std::size_t>(elementMaterials_[i])];
  HexElementEnergy result = hexIsotropicHyperelastic(gaussPoints_[i], deformed, material, withTangent);
  if (std::isfinite(result.energy) && result.force.allFinite() && (!withTangent || result.tangent.allFinite())) {
    return result;
  }
  double smallest = std::numeric_limits<double>::infinity();
  for (const Eigen::Matrix<double, 3, 8>& gradients : gaussPoints_[i].gradients) {
    smallest = std::min(smallest, (deformed * gradients.transpose()).determinant());
  }
  std::ostringstream message;
  message << name() << ": element " << e << " has a non-finite energy, force or tangent (smallest J = det F at its "
          << "Gauss points " << smallest << "); enable inversion handling (an inversion threshold in (0, 1)) or "
          << "reduce the step";
  throw NumericalError(message.str());
}

std::unique_ptr<ForceModel> makeHexHyperelasticForceModel(const TetMesh& mesh, HyperelasticMaterialKind kind,
                                                          const HyperelasticOptions& options) {
  if (kind != HyperelasticMaterialKind::stvk || options.stvkFormulation != StVKFormulation::greenStrain) {
    return std::make_unique<HexHyperelasticForceModel>(mesh, kind, options);
  }
  if (options.inversionHandlingEnabled() || options.enableCompressionResistance || options.enforceSPD) {
    throw ValidationError(
        "stvk in the Green-strain form (HexStvkForceModel) has no inversion threshold, compression resistance or "
        "enforceSPD: choose the principal-stretch formulation for them");
  }
  return std::make_unique<HexStvkForceModel>(mesh);
}

}  // namespace asyncfem
