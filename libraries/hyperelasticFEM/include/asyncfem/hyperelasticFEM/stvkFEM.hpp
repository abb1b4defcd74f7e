// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/hyperelasticFEM/elementForceModel.hpp>
#include <asyncfem/hyperelasticFEM/hyperelasticOptions.hpp>
#include <atomic>
#include <memory>
#include <vector>

namespace asyncfem {

/// Saint Venant-Kirchhoff FEM on linear tetrahedra in the Green-strain form, the model
/// of Vega FEM's StVKForceModel (which precomputes polynomial integrals of the same
/// quantities). Per element, with F = sum_a x_a g_a^T, E = (F^T F - I) / 2 and the Lame
/// parameters of the element's material (vegaLameParameters(E, nu)):
///   - energy |V| (lambda/2 (tr E)^2 + mu tr(E^2));
///   - second Piola-Kirchhoff stress S = lambda tr(E) I + 2 mu E, first P = F S;
///   - force on vertex a: |V| P g_a;
///   - tangent block (a, b): |V| [ (g_a . S g_b) I + lambda h_a h_b^T
///     + mu (g_a . g_b) F F^T + mu h_b h_a^T ], h_a = F g_a (exact derivative, symmetric).
/// At F = I the tangent is linear FEM's element stiffness. StVK softens under strong
/// compression and has no resistance to inversion; use IsotropicHyperelasticFEM with an
/// inversion threshold when elements may invert.
class StVKFEM final : public ElementForceModel {
 public:
  /// Throws ValidationError naming the lowest degenerate element; assembler as in
  /// ElementForceModel (null: built here). batchedKernel: the tangent pass evaluates four
  /// elements at a time (SIMD lanes over elements; HyperelasticOptions::batchedKernel),
  /// equal to one element at a time to rounding.
  explicit StVKFEM(const TetMesh& mesh, std::shared_ptr<const MatrixAssembler> assembler = nullptr,
                   bool batchedKernel = true);

  /// Lame parameters of element e.
  const LameParameters& elementLame(int e) const { return lame_[static_cast<std::size_t>(e)]; }
  /// Elements evaluated by the batched kernel since construction (all evaluations
  /// together), for tests and tools.
  long long batchedElements() const { return batchedElements_.load(std::memory_order_relaxed); }

 protected:
  void computeElement(int element, const Eigen::Matrix3d& deformationGradient, double* energy, ElementVector* force,
                      ElementMatrix* tangent) const override;
  void computeBatch(int first, int count, const Eigen::Matrix3d* deformationGradients, ElementVector* forces,
                    ElementMatrix* tangents) const override;

 private:
  std::vector<LameParameters> lame_;
  bool batchedKernel_ = true;
  mutable std::atomic<long long> batchedElements_{0};
};

}  // namespace asyncfem
