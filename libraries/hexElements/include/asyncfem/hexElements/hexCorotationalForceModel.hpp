// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/hexElements/hexForceModel.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

namespace asyncfem {

/// Corotated linear FEM on a hexahedral mesh (hexCorotational per element, the rotation of
/// each element's centre), as a HexForceModel: forces are the exact gradient of the energy;
/// the tangent is R K_e R^T (simpleTangent, the default) or the derivative of R K_e v
/// (hexCorotational()). The linear element stiffness and the centre's shape-function
/// gradients are computed once. Throws ValidationError on a tetrahedral mesh and, naming
/// the element, for a rest shape with det J <= 0 at a Gauss point.
class HexCorotationalForceModel : public HexForceModel {
 public:
  explicit HexCorotationalForceModel(const TetMesh& mesh, bool simpleTangent = true);
  bool isLinear() const override { return false; }

 protected:
  HexElementEnergy element(Eigen::Index e, const HexElementPositions& rest, const HexElementPositions& deformed,
                           bool withTangent) const override;

 private:
  bool simpleTangent_;
  std::vector<HexElementMatrix> stiffness_;                   ///< K_e per element
  std::vector<Eigen::Matrix<double, 3, 8>> centreGradients_;  ///< g_a at xi = 0 per element
};

}  // namespace asyncfem
