// SPDX-License-Identifier: BSD-3-Clause
// The interface elements of the stable coupling. Private to the library.
#pragma once

#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/dynamics/dynamicSystem.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

#include "detail/fastRegion.hpp"

namespace asyncfem::detail {

/// Fills each region's interfaceElements: the elements with vertices in S_i and in L, with
/// their constant linear stiffness when the force model has no per-element tangent (linear
/// models built from a matrix). Then the model's K must be the mesh's linear FEM
/// stiffness, which is checked on every column of an interface DOF (relative 1e-10: the
/// same element matrices summed in another order differ by round-off, ~1e-15; a different
/// material or a scaled K differs by far more; asyncfem::ValidationError otherwise, and
/// for a nonlinear model without element tangents). Returns whether the force model gives
/// per-element tangents (then they are recomputed at every rebuild). knownStiffness, when
/// given, is the linear model's K already evaluated (the check then reads it instead of
/// asking the model for a new copy).
bool findInterfaceElements(const TetMesh& mesh, const RegionPartition& partition, const DynamicSystem& system,
                           std::vector<FastRegion>& regions,
                           const Eigen::SparseMatrix<double>* knownStiffness = nullptr);

}  // namespace asyncfem::detail
