// SPDX-License-Identifier: BSD-3-Clause
#include "detail/elementTangents.hpp"

#include <asyncfem/core/error.hpp>

#include "detail/meshElements.hpp"

namespace asyncfem::detail {

ElementTangents::ElementTangents(const TetMesh& mesh, const ForceModel& model, const std::string& who,
                                 const std::string& hint)
    : mesh_(mesh), model_(model) {
  Eigen::MatrixXd probe;
  perElement_ =
      mesh.numElements() > 0 && model.elementTangentOfAnyKind(Eigen::VectorXd::Zero(mesh.numDofs()), 0, probe);
  if (!perElement_ && !model.isLinear()) {
    throw ValidationError(who +
                          ": the coupling needs each element's tangent, and this nonlinear force model gives none "
                          "(ForceModel::elementTangent)" +
                          (hint.empty() ? "" : "; " + hint));
  }
}

void ElementTangents::tangent(const Eigen::VectorXd& u, int e, Eigen::MatrixXd& out) const {
  if (perElement_) {
    model_.elementTangentOfAnyKind(u, e, out);
    return;
  }
  out = linear(e);
}

Eigen::MatrixXd ElementTangents::linear(int e) const { return linearStiffnessOf(mesh_, e); }

}  // namespace asyncfem::detail
