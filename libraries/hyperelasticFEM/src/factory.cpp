// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/hyperelasticFEM/factory.hpp>
#include <asyncfem/hyperelasticFEM/isotropicHyperelasticFEM.hpp>
#include <asyncfem/hyperelasticFEM/stvkFEM.hpp>

namespace asyncfem {

std::unique_ptr<ForceModel> makeHyperelasticForceModel(const TetMesh& mesh, HyperelasticMaterialKind kind,
                                                       const HyperelasticOptions& options,
                                                       std::shared_ptr<const MatrixAssembler> assembler) {
  if (kind == HyperelasticMaterialKind::stvk && options.stvkFormulation == StVKFormulation::greenStrain) {
    if (options.inversionHandlingEnabled() || options.enableCompressionResistance || options.enforceSPD) {
      throw ValidationError(
          "stvk in the Green-strain form has no inversion threshold, compression resistance or enforceSPD: choose "
          "the principal-stretch formulation for them");
    }
    return std::make_unique<StVKFEM>(mesh, std::move(assembler), options.batchedKernel);
  }
  return std::make_unique<IsotropicHyperelasticFEM>(mesh, kind, options, std::move(assembler));
}

}  // namespace asyncfem
