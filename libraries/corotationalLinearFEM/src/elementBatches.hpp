// SPDX-License-Identifier: BSD-3-Clause
// Pass 1 of CorotationalLinearFEM (deformation gradient, rotation, corotated stress,
// element forces and rotated gradients) for kElementLanes elements at a time: every scalar
// of the per-element computation becomes an Eigen array over lanes, so the compiler emits
// packed SSE2 / AVX instructions, whichever the build enables. The element geometry is
// stored per batch in structure-of-arrays form. Each lane follows the scalar path's
// arithmetic (same Newton iteration, start, convergence rule and tolerances, see
// polarRotation()), so the results equal the scalar ones to rounding; a lane the Newton
// iteration does not settle (SVD fallback, non-finite input) takes the scalar
// polarRotation().
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

namespace asyncfem::detail {

inline constexpr int kElementLanes = 4;
using Lanes = Eigen::Array<double, kElementLanes, 1>;

/// Element geometry in batches of kElementLanes consecutive elements (the remainder of
/// numElements / kElementLanes is left to the scalar path).
struct ElementBatches {
  int numBatches = 0;
  /// Vertex a of lane l of batch k at vertices[16 k + 4 a + l].
  std::vector<int> vertices;
  /// g(j, a) (shape-function gradients) of batch k at gradients[12 k + 3 a + j].
  std::vector<Lanes> gradients;
  /// lambda V and mu V of batch k at lameVolume[2 k] and [2 k + 1].
  std::vector<Lanes> lameVolume;
};

ElementBatches makeElementBatches(const Eigen::Matrix4Xi& elements,
                                  const std::vector<Eigen::Matrix<double, 3, 4>>& shapeGradients,
                                  const std::vector<Eigen::Vector2d>& lameVolume);

/// Where evaluateBatch() writes element e's results (the per-element arrays of
/// CorotationalLinearFEM); differentialOperators is null unless the exact tangent needs it.
struct BatchOutputs {
  Eigen::Matrix3d* rotations = nullptr;
  Eigen::Matrix3d* differentialOperators = nullptr;
  double* energies = nullptr;
  Eigen::Matrix<double, 3, 4>* rotatedGradients = nullptr;
  Eigen::Matrix<double, 3, 4>* forces = nullptr;
};

struct BatchCounters {
  long long newtonSteps = 0;
  long long fallbacks = 0;
};

/// Pass 1 for the elements of batch (kElementLanes batch + lane), rotations started from
/// the deformation (RotationStart::fromDeformation).
void evaluateBatch(const ElementBatches& batches, int batch, const Eigen::VectorXd& displacement,
                   const BatchOutputs& outputs, BatchCounters& counters);

}  // namespace asyncfem::detail
