// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/forceModel/forceModel.hpp>
#include <asyncfem/hexElements/hexForceModel.hpp>
#include <asyncfem/hexElements/hexHyperelastic.hpp>
#include <asyncfem/hyperelasticFEM/hyperelasticOptions.hpp>
#include <asyncfem/hyperelasticFEM/isotropicMaterialPoint.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <memory>
#include <optional>
#include <vector>

namespace asyncfem {

/// The isotropic hyperelastic materials of library hyperelasticFEM (StVK through principal
/// stretches, neo-Hookean, Mooney-Rivlin) on a hexahedral mesh, as a HexForceModel:
/// hexIsotropicHyperelastic per element (2 x 2 x 2 Gauss points), the material law of
/// IsotropicMaterialPoint with the options of the tetrahedral IsotropicHyperelasticFEM
/// (inversion threshold and handling, compression resistance, enforceSPD, the Mooney-Rivlin
/// override, the invariant path; batchedKernel is not read). The rest shapes' Gauss-point
/// gradients are computed once.
class HexHyperelasticForceModel : public HexForceModel {
 public:
  /// Throws ValidationError on a tetrahedral mesh, for out-of-range options, for a
  /// Mooney-Rivlin element without parameters and for a rest shape with det J <= 0 at a
  /// Gauss point (naming the element).
  HexHyperelasticForceModel(const TetMesh& mesh, HyperelasticMaterialKind kind,
                            const HyperelasticOptions& options = {});
  bool isLinear() const override { return false; }
  HyperelasticMaterialKind kind() const { return kind_; }
  const HyperelasticOptions& options() const { return options_; }

 protected:
  /// Throws NumericalError naming the element when its energy, force or tangent is not
  /// finite (a flat Gauss point without inversion handling).
  HexElementEnergy element(Eigen::Index e, const HexElementPositions& rest, const HexElementPositions& deformed,
                           bool withTangent) const override;

 private:
  HyperelasticMaterialKind kind_;
  HyperelasticOptions options_;
  std::vector<std::optional<IsotropicMaterialPoint>> materials_;  ///< per material of the mesh; unused: empty
  std::vector<int> elementMaterials_;
  std::vector<HexGaussPoints> gaussPoints_;  ///< per element
};

/// The force model of a hyperelastic material on a hexahedral mesh, as
/// makeHyperelasticForceModel on tetrahedra: stvk in the Green-strain form is
/// HexStvkForceModel (an enabled inversion threshold, compression resistance or enforceSPD
/// is then a ValidationError saying to choose the principal-stretch formulation); every
/// other case HexHyperelasticForceModel.
std::unique_ptr<ForceModel> makeHexHyperelasticForceModel(const TetMesh& mesh, HyperelasticMaterialKind kind,
                                                          const HyperelasticOptions& options = {});

}  // namespace asyncfem
