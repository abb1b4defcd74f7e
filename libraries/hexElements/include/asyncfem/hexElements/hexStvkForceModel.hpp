// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/hexElements/hexForceModel.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

namespace asyncfem {

/// Saint Venant-Kirchhoff FEM on a hexahedral mesh (the Green-strain form of hexStvk,
/// 2 x 2 x 2 Gauss points per element), as a HexForceModel. The tangent is the exact
/// derivative of the forces.
///
/// No inversion handling (StVK's energy softens under strong compression, as Vega's
/// StVKForceModel). Throws ValidationError on a tetrahedral mesh and, naming the element,
/// for a rest shape with det J <= 0 at a Gauss point. Keeps each element's rest Gauss-point
/// data (hexGaussPoints, 1.6 kB per element), so that an evaluation does not recompute them.
class HexStvkForceModel : public HexForceModel {
 public:
  explicit HexStvkForceModel(const TetMesh& mesh);
  bool isLinear() const override { return false; }

 protected:
  HexElementEnergy element(Eigen::Index e, const HexElementPositions& rest, const HexElementPositions& deformed,
                           bool withTangent) const override;

 private:
  std::vector<Eigen::Vector2d> lame_;        ///< per element: (lambda, mu)
  std::vector<HexGaussPoints> gaussPoints_;  ///< per element: the rest shape at the Gauss points
};

}  // namespace asyncfem
