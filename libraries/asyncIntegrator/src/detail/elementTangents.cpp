// SPDX-License-Identifier: BSD-3-Clause
#include "detail/elementTangents.hpp"

#include <asyncfem/core/error.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>

namespace asyncfem::detail {

ElementTangents::ElementTangents(const TetMesh& mesh, const ForceModel& model, const std::string& who,
                                 const std::string& hint)
    : mesh_(mesh), model_(model) {
  Eigen::Matrix<double, 12, 12> probe;
  perElement_ = mesh.numElements() > 0 && model.elementTangent(Eigen::VectorXd::Zero(mesh.numDofs()), 0, probe);
  if (!perElement_ && !model.isLinear()) {
    throw ValidationError(who +
                          ": the coupling needs each element's tangent, and this nonlinear force model gives none "
                          "(ForceModel::elementTangent)" +
                          (hint.empty() ? "" : "; " + hint));
  }
}

void ElementTangents::tangent(const Eigen::VectorXd& u, int e, Eigen::Matrix<double, 12, 12>& out) const {
  if (perElement_) {
    model_.elementTangent(u, e, out);
    return;
  }
  out = linear(e);
}

Eigen::Matrix<double, 12, 12> ElementTangents::linear(int e) const {
  const Material& material = mesh_.elementMaterial(e);
  return linearElementStiffness(mesh_.elementRestPositions(e), material.youngsModulus, material.poissonRatio);
}

}  // namespace asyncfem::detail
