// SPDX-License-Identifier: BSD-3-Clause
// The invariant kernel (invariantKernel.hpp, Eqs. K1 and K2) for four elements at once:
// every scalar of the element computation is a value per element ("lane"), stored and
// combined four at a time, so the compiler emits packed arithmetic (two SSE2 or one AVX
// instruction per operation) from plain loops over the lanes. Results equal the
// one-element kernel's to rounding (HyperelasticBatchedKernel.* tests).
#pragma once

#include <Eigen/Core>
#include <asyncfem/hyperelasticFEM/hyperelasticOptions.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>

#include "isotropicMaterials.hpp"

namespace asyncfem::detail {

/// Elements evaluated together by batchedInvariantTerms.
constexpr int kLanes = 4;

/// Inputs of one batch: the elements' deformation gradients, rest volumes and shape
/// gradients (3x4, columns the gradients of the vertices' shape functions), all of one
/// material.
struct ElementBatchInput {
  const Eigen::Matrix3d* deformationGradients;        // kLanes of them
  const double* volumes;                              // kLanes
  const Eigen::Matrix<double, 3, 4>* shapeGradients;  // kLanes
};

/// For each lane l: forces[l] (when forces is not null) = |V| P g_a stacked per vertex, and
/// tangents[l] = |V| G^T (dP/dF) G, exactly symmetric (its lower triangle mirrored); every
/// element must satisfy invariantPathApplies (det F > 0).
void batchedInvariantTerms(HyperelasticMaterialKind kind, const IsotropicMaterialConstants& constants,
                           const ElementBatchInput& input, ElementVector* forces, ElementMatrix* tangents);

}  // namespace asyncfem::detail
