// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/forceModel/forceModel.hpp>
#include <asyncfem/hyperelasticFEM/hyperelasticOptions.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <memory>

namespace asyncfem {

/// The force model of a hyperelastic material on mesh, for the scene layer:
///   - stvk with options.stvkFormulation == greenStrain: StVKFEM (Vega's StVKForceModel);
///     then an enabled inversion threshold, compression resistance or enforceSPD is an
///     error (ValidationError saying to choose the principal-stretch formulation);
///   - every other case: IsotropicHyperelasticFEM(mesh, kind, options).
/// assembler: share one with the mass matrix (null: the model builds its own).
std::unique_ptr<ForceModel> makeHyperelasticForceModel(const TetMesh& mesh, HyperelasticMaterialKind kind,
                                                       const HyperelasticOptions& options = {},
                                                       std::shared_ptr<const MatrixAssembler> assembler = nullptr);

}  // namespace asyncfem
