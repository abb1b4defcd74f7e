// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/hyperelasticFEM/elementForceModel.hpp>
#include <asyncfem/hyperelasticFEM/hyperelasticOptions.hpp>
#include <atomic>
#include <memory>
#include <vector>

namespace asyncfem {

namespace detail {
struct IsotropicMaterialConstants;
}

/// Principal stretches of a deformation gradient with the reflection fix-up of Irving,
/// Teran & Fedkiw 2004: F = U diag(s) V^T with U, V rotations (det +1) and s sorted by
/// decreasing magnitude; if det F < 0 the smallest stretch is negative.
struct SignedSvd {
  Eigen::Matrix3d u;
  Eigen::Vector3d stretches;
  Eigen::Matrix3d v;
};
SignedSvd signedSvd(const Eigen::Matrix3d& deformationGradient);

/// Isotropic hyperelastic FEM through principal stretches, with inversion handling
/// (Irving, Teran & Fedkiw 2004; Teran, Sifakis, Irving & Fedkiw 2005), the model of
/// Vega FEM's IsotropicHyperelasticFEM for its StVK, neo-Hookean and Mooney-Rivlin
/// materials (HyperelasticMaterialKind; energy densities W in hyperelasticOptions.hpp).
///
/// Per element with F = sum_a x_a g_a^T = U diag(s) V^T (signedSvd()):
///   - energy |V| W(s) and first Piola-Kirchhoff stress P = U diag(dW/ds) V^T; the force
///     on vertex a is |V| P g_a (Vega's sign: f_int opposes the deformation);
///   - the tangent from dP/dF in the rotated frame (Teran et al. 2005, Sec. 6-7): the
///     3x3 block d^2W/ds^2 acting on the diagonal of U^T dF V and, for each pair i < j,
///     the 2x2 block [[a, b], [b, a]] acting on its (i, j), (j, i) entries, with
///     eigenvalues a + b = (g_i - g_j)/(s_i - s_j) and a - b = (g_i + g_j)/(s_i + s_j)
///     (Vega's closed forms in the invariants' derivatives, no division by s_i - s_j);
///   - K_e = |V| D^T A D with D the 9x12 map of vertex displacements to U^T dF V.
/// Below options.inversionThreshold the stretches are handled as InversionHandling says.
/// With enforceSPD each element's A has its negative eigenvalues set to zero.
///
/// Material parameters: Lame parameters of each element's (E, nu) as Vega computes them
/// (vegaLameParameters) for stvk and neo-Hookean; for Mooney-Rivlin the material's
/// MooneyRivlinParameters or options.mooneyRivlin.
class IsotropicHyperelasticFEM final : public ElementForceModel {
 public:
  /// Throws ValidationError for a degenerate element, an out-of-range option (inversion
  /// threshold not in (0, 1) nor disabled, negative or non-finite compression
  /// resistance) or a Mooney-Rivlin element without parameters (naming the element and
  /// its material).
  IsotropicHyperelasticFEM(const TetMesh& mesh, HyperelasticMaterialKind kind, const HyperelasticOptions& options = {},
                           std::shared_ptr<const MatrixAssembler> assembler = nullptr);
  ~IsotropicHyperelasticFEM() override;

  HyperelasticMaterialKind kind() const { return kind_; }
  const HyperelasticOptions& options() const { return options_; }
  /// Energy density W (per rest volume) of element e at principal stretches s, with the
  /// inversion handling of the options; for tests and tools.
  double energyDensity(int element, const Eigen::Vector3d& stretches) const;
  /// Elements whose tangent went through the batched kernel since construction (all
  /// evaluations together; options().batchedKernel), for tests and tools.
  long long batchedElements() const { return batchedElements_.load(std::memory_order_relaxed); }

 protected:
  void computeElement(int element, const Eigen::Matrix3d& deformationGradient, double* energy, ElementVector* force,
                      ElementMatrix* tangent) const override;
  /// Four elements of one material that all take the invariant path go through the
  /// batched kernel (options().batchedKernel); any other batch one element at a time.
  void computeBatch(int first, int count, const Eigen::Matrix3d* deformationGradients, ElementVector* forces,
                    ElementMatrix* tangents) const override;

 private:
  /// computeElement for an element where options_.invariantPath applies (invariantKernel.hpp).
  void computeElementFromInvariants(int element, const Eigen::Matrix3d& deformationGradient, double* energy,
                                    ElementVector* force, ElementMatrix* tangent) const;

  HyperelasticMaterialKind kind_;
  HyperelasticOptions options_;
  std::vector<detail::IsotropicMaterialConstants> constants_;  // per material of the mesh
  std::vector<int> elementMaterials_;
  mutable std::atomic<long long> batchedElements_{0};
};

}  // namespace asyncfem
