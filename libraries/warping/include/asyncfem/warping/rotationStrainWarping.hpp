// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <asyncfem/warping/warping.hpp>
#include <memory>
#include <vector>

namespace asyncfem {

namespace detail {
struct ElementGeometry;
}  // namespace detail

/// Rotation-strain coordinate warping (Huang, Tong, Wei & Bao 2011; used to display the
/// linear FEM results of Zhao, Li & Barbič 2016).
///
/// Per element e (linear tetrahedron, constant gradient; or trilinear hexahedron, gradient at
/// its centre) the displacement gradient
///     G_e = sum_a u_a (grad N_a)^T                           (3x3, dimensionless)
/// is split into its skew and symmetric parts,
///     W_e = (G_e - G_e^T) / 2 = [omega_e]x,   S_e = (G_e + G_e^T) / 2,
/// i.e. an infinitesimal rotation vector omega_e (radians) and a small strain S_e. The
/// rotation is then taken finitely, R_e = exp([omega_e]x) (Rodrigues' formula), and the
/// element's target deformation gradient is F_e = R_e (I + S_e). For a linear field the
/// F_e generally do not come from one position field, so positions are recovered in the
/// least-squares sense (a Poisson problem):
///     minimise  sum_e V_e || grad w |_e - (F_e - I) ||_F^2   over the warped displacement w,
/// whose normal equations are L w = b, one right-hand side per coordinate, with the
/// scalar volume Laplacian L_ab = sum_e V_e grad N_a . grad N_b (n x n, units of length)
/// and b_a = sum_e V_e (F_e - I) grad N_a. On hexahedra the gradient of w varies over the
/// element and both are integrals over it, L_ab = sum_e int_e grad N_a . grad N_b and
/// b_a = sum_e (F_e - I) int_e grad N_a (2 x 2 x 2 Gauss points; one point would leave
/// hourglass modes in L). The constraints:
/// - fixed vertices (constructor argument) keep the displacement given to warp() (zero in
///   a simulation's output);
/// - a connected component of the mesh without fixed vertices is translation-free: its
///   lowest vertex id is pinned during the solve and the component is then translated so
///   that its mean displacement (plain average over its vertices) equals that of the
///   linear input. Rotating the input by a rigid motion therefore keeps the output's
///   centroid where the linear result puts it.
/// Vertices that no element uses are passed through unchanged.
///
/// L restricted to the unconstrained vertices is symmetric positive definite and is
/// factored once by the constructor; warp() costs one element pass plus one forward and
/// back substitution with three right-hand sides.
///
/// Properties (tests/warping): u = 0 gives w = 0 exactly; a translation stays that
/// translation (to rounding); the linearised rigid rotation u = theta [a]x (X - c) gives
/// G_e = theta [a]x, S_e = 0, F_e = exp(theta [a]x), hence an exactly rigid result.
class RotationStrainWarping final : public Warping {
 public:
  /// mesh: every element must have non-zero volume (asyncfem::ValidationError naming the
  /// first degenerate one); fixedVertices: 0-based, any order, duplicates allowed
  /// (ValidationError naming one out of range). solver: the factorization of L.
  explicit RotationStrainWarping(const TetMesh& mesh, const std::vector<int>& fixedVertices = {},
                                 SolverKind solver = SolverKind::cholmod);
  ~RotationStrainWarping() override;
  RotationStrainWarping(RotationStrainWarping&&) noexcept;
  RotationStrainWarping& operator=(RotationStrainWarping&&) noexcept;

  WarpingKind kind() const override { return WarpingKind::rotationStrain; }
  int numVertices() const override { return numVertices_; }
  /// Warped displacement (3n) for a linear displacement (3n); see the class comment.
  Eigen::VectorXd warp(const Eigen::Ref<const Eigen::VectorXd>& displacement) override;

  /// Number of unknowns of the factored system (vertices neither fixed nor pinned).
  int numUnknowns() const { return static_cast<int>(unknownVertices_.size()); }
  /// Connected components (through shared element vertices) of the used vertices.
  int numComponents() const { return static_cast<int>(componentPinned_.size()); }
  /// Statistics of the factorization of L (non-zeros of the factor, flops...).
  const SolverStats& solverStats() const;

 private:
  /// Set-up steps of the constructor, in order. used: vertex is in some element;
  /// fixed: vertex is in fixedVertices. The index vectors map a vertex to its row among
  /// the unknown or the constrained vertices (-1: not one).
  void findComponents(const std::vector<bool>& used, const std::vector<bool>& fixed);
  void numberVertices(const std::vector<bool>& used, const std::vector<bool>& fixed, std::vector<int>& unknownIndex,
                      std::vector<int>& constrainedIndex);
  void factorLaplacian(const TetMesh& mesh, const detail::ElementGeometry& geometry,
                       const std::vector<int>& unknownIndex, const std::vector<int>& constrainedIndex,
                       SolverKind solverKind);
  void buildGatherMap(const TetMesh& mesh);
  /// Stages of warp() for the displacement u (3 x n).
  void elementPass(const Eigen::Map<const Eigen::Matrix3Xd>& u);
  void gatherRightHandSide(const Eigen::Map<const Eigen::Matrix3Xd>& u);
  void shiftPinnedComponents(const Eigen::Map<const Eigen::Matrix3Xd>& u, Eigen::VectorXd& warped) const;

  int numVertices_ = 0;
  int numElements_ = 0;
  int verticesPerElement_ = 4;  // k: 4 (tetrahedra) or 8 (hexahedra)
  Eigen::MatrixXi elements_;    // k x numElements
  // Columns k e + a: grad N_a at element e's centre (1 / length), and its integral over the
  // element (length^2; V_e grad N_a for a tetrahedron).
  Eigen::Matrix3Xd centreGradients_;
  Eigen::Matrix3Xd integratedGradients_;
  // Gather map for b: the elements around vertex v are adjacencyOffsets_[v] ..
  // adjacencyOffsets_[v+1] in adjacencySlots_, each stored as k e + local index.
  std::vector<int> adjacencyOffsets_;
  std::vector<int> adjacencySlots_;

  std::vector<int> component_;         // vertex -> component id, -1 unused
  std::vector<bool> componentPinned_;  // component has no fixed vertex: translation pinned
  std::vector<std::vector<int>> componentVertices_;
  std::vector<int> constrainedVertices_;  // fixed and pinned vertices, ascending
  std::vector<int> unknownVertices_;      // the rest of the used vertices, ascending
  std::vector<int> unusedVertices_;
  Eigen::SparseMatrix<double> laplacianUnknownConstrained_;  // L(unknown, constrained)
  std::unique_ptr<SparseSolver> solver_;                     // factor of L(unknown, unknown)

  // Per-frame scratch, kept to avoid allocations.
  Eigen::Matrix<double, 3, Eigen::Dynamic> elementRightHandSides_;  // 3 x k numElements
  Eigen::MatrixXd rightHandSide_;                                   // numUnknowns x 3
  Eigen::MatrixXd solution_;
};

}  // namespace asyncfem
