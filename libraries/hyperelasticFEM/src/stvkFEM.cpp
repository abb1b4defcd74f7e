// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/hyperelasticFEM/stvkFEM.hpp>

#include "detail/batchedStvkKernel.hpp"

namespace asyncfem {

StVKFEM::StVKFEM(const TetMesh& mesh, std::shared_ptr<const MatrixAssembler> assembler, bool batchedKernel)
    : ElementForceModel(mesh, std::move(assembler), "StVKFEM"), batchedKernel_(batchedKernel) {
  const int count = mesh.numElements();
  lame_.resize(static_cast<std::size_t>(count));
  for (int e = 0; e < count; ++e) {
    const Material& material = mesh.elementMaterial(e);
    lame_[static_cast<std::size_t>(e)] = vegaLameParameters(material.youngsModulus, material.poissonRatio);
  }
}

void StVKFEM::computeElement(int element, const Eigen::Matrix3d& deformationGradient, double* energy,
                             ElementVector* force, ElementMatrix* tangent) const {
  const auto i = static_cast<std::size_t>(element);
  const LameParameters& lame = lame_[i];
  const double volume = geometry().volumes[i];
  const Eigen::Matrix<double, 3, 4>& g = geometry().shapeGradients[i];
  const Eigen::Matrix3d& f = deformationGradient;
  const Eigen::Matrix3d strain = 0.5 * (f.transpose() * f - Eigen::Matrix3d::Identity());
  const double trace = strain.trace();
  if (energy != nullptr) *energy = volume * ((0.5 * lame.lambda * trace * trace) + (lame.mu * strain.squaredNorm()));
  if (force == nullptr && tangent == nullptr) return;
  Eigen::Matrix3d stress = (2.0 * lame.mu) * strain;  // S
  stress.diagonal().array() += lame.lambda * trace;
  if (force != nullptr) {
    const Eigen::Matrix<double, 3, 4> nodal = volume * (f * stress) * g;  // |V| P g_a
    *force = Eigen::Map<const ElementVector>(nodal.data());
  }
  if (tangent != nullptr) {
    const Eigen::Matrix<double, 3, 4> h = f * g;                   // h_a = F g_a
    const Eigen::Matrix4d geometric = g.transpose() * stress * g;  // g_a . S g_b
    const Eigen::Matrix4d gradientDots = g.transpose() * g;        // g_a . g_b
    const Eigen::Matrix3d leftCauchyGreen = f * f.transpose();     // F F^T
    for (int b = 0; b < 4; ++b) {
      for (int a = 0; a < 4; ++a) {
        Eigen::Matrix3d block = (lame.lambda * h.col(a)) * h.col(b).transpose();
        block.noalias() += (lame.mu * h.col(b)) * h.col(a).transpose();
        block += (lame.mu * gradientDots(a, b)) * leftCauchyGreen;
        block.diagonal().array() += geometric(a, b);
        tangent->block<3, 3>(3 * a, 3 * b) = volume * block;
      }
    }
  }
}

void StVKFEM::computeBatch(int first, int count, const Eigen::Matrix3d* deformationGradients, ElementVector* forces,
                           ElementMatrix* tangents) const {
  if (!batchedKernel_ || count != detail::kStvkLanes) {
    ElementForceModel::computeBatch(first, count, deformationGradients, forces, tangents);
    return;
  }
  const auto e0 = static_cast<std::size_t>(first);
  batchedElements_.fetch_add(count, std::memory_order_relaxed);
  detail::batchedStvkTerms(deformationGradients, &geometry().volumes[e0], &geometry().shapeGradients[e0], &lame_[e0],
                           forces, tangents);
}

}  // namespace asyncfem
