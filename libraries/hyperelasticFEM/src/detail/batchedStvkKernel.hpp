// SPDX-License-Identifier: BSD-3-Clause
// StVKFEM's element terms (stvkFEM.hpp) for four elements at once: every scalar of the
// element computation is stored per element ("lane") and combined in plain loops over the
// lanes, which the compiler turns into packed arithmetic. Results equal the one-element
// computation's to rounding (StVKBatchedKernel.* tests).
#pragma once

#include <Eigen/Core>
#include <asyncfem/hyperelasticFEM/hyperelasticOptions.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>

namespace asyncfem::detail {

/// Elements evaluated together by batchedStvkTerms.
constexpr int kStvkLanes = 4;

/// For each of the kStvkLanes elements l (deformation gradient F_l, rest volume, shape
/// gradients g, Lame parameters): forces[l] (when forces is not null) = |V| F S g_a per
/// vertex a, and tangents[l] = the exactly symmetric 12x12 tangent of stvkFEM.hpp (its
/// lower block triangle computed, the upper mirrored).
void batchedStvkTerms(const Eigen::Matrix3d* deformationGradients, const double* volumes,
                      const Eigen::Matrix<double, 3, 4>* shapeGradients, const LameParameters* lame,
                      ElementVector* forces, ElementMatrix* tangents);

}  // namespace asyncfem::detail
