// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/forceModel/forceModel.hpp>
#include <asyncfem/petscBackend/petscSimulation.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <functional>
#include <memory>
#include <vector>

namespace asyncfem::detail {

/// The sub-mesh of elements (ascending mesh ids): their vertices in ascending mesh id
/// (meshVertex, filled), the materials as they are.
TetMesh subMesh(const TetMesh& mesh, const std::vector<int>& elements, std::vector<int>& meshVertex);

/// The single-process force model of kind on mesh (corotational with tangent; the
/// hyperelastic materials with their options), so that a rank's elements go through the
/// same kernels as a one-process run's. Throws Error for the linear kind (no element loop).
std::unique_ptr<ForceModel> makeSubMeshModel(const TetMesh& mesh, PetscForceModelKind kind, TangentKind tangent,
                                             const HyperelasticOptions& hyperelastic);

/// Runs work; an asyncfem error it throws is thrown again with the same type and every
/// "element N" of its message (a sub-mesh element) replaced by meshElement[N], the mesh's id.
void inMeshNumbering(const std::vector<int>& meshElement, const std::function<void()>& work);

}  // namespace asyncfem::detail
