// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/forceModel/forceModel.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <memory>
#include <vector>

namespace asyncfem {

namespace detail {
struct ElementBatches;
}

/// Which tangent stiffness CorotationalLinearFEM returns.
enum class TangentKind {
  /// K_e^R = R K_e R^T (R acting block-wise on the four vertices): the rotated linear
  /// stiffness, ignoring how R changes with x. Symmetric positive semi-definite; Vega
  /// FEM's default. Not the derivative of the forces once elements are strained.
  simple,
  /// The full derivative d f_e / d x, including dR / dx (see CorotationalLinearFEM).
  /// Symmetric (it is the Hessian of the energy) but may be indefinite under strong
  /// compression or inversion.
  exact,
};

/// Where the Newton iteration of each element's rotation starts (see polarRotation()).
enum class RotationStart {
  /// A guess computed from the element's deformation gradient alone: every result is a
  /// function of the displacement only, so runs restarted from a checkpoint repeat an
  /// uninterrupted run bit for bit. The default.
  fromDeformation,
  /// The element's rotation at the previous evaluation (warm start, Mueller et al.
  /// 2016): fewer Newton steps under smooth motion, but the results then depend on the
  /// history of evaluations at the level of rounding.
  previousEvaluation,
};

/// How pass 1 (see CorotationalLinearFEM) evaluates the elements.
enum class ElementKernel {
  /// Four elements at a time, each scalar of the element computation an array over the
  /// four (packed SIMD arithmetic), the geometry stored per batch of four at construction;
  /// the last numElements % 4 elements, and every element under
  /// RotationStart::previousEvaluation, take the scalar path. Equal to the scalar path to
  /// rounding (the same Newton iteration, start and stopping rule per element; an element
  /// that needs the SVD fallback takes the scalar polarRotation()). The default.
  batched,
  /// One element at a time.
  scalar,
};

/// Counters of the rotation extractions since construction.
struct RotationStats {
  long long extractions = 0;             ///< element rotations computed
  long long newtonSteps = 0;             ///< Newton steps over all of them
  long long decompositionFallbacks = 0;  ///< extractions that fell back to the SVD
  long long reusedEvaluations = 0;       ///< evaluations served from the cache (same displacement)
};

/// Corotated linear FEM on linear tetrahedra (Mueller & Gross 2004; the model of Vega
/// FEM's corotational linear FEM).
///
/// Per element e with rest positions X (12-vector, the four vertices stacked), current
/// positions x = X + u (12), shape-function gradients g_a (rest configuration) and the
/// linear element stiffness K_e (12x12, from linearElementStiffness, cached at
/// construction):
///   - deformation gradient F = sum_a x_a g_a^T = Ds Dm^{-1} (3x3, dimensionless);
///   - rotation R from the polar decomposition F = R S (polarRotation(): Newton on SO(3)
///     with an SVD fallback, the R of polarDecomposition() with its sign fix, det R = +1
///     also for flat and inverted elements);
///   - internal force f_e = R K_e (R^T x - X) (12, force units, e.g. N), R acting on
///     each vertex's 3-vector; assembled f_int = sum_e f_e, Vega's sign convention
///     (f_int opposes the deformation, see ForceModel);
///   - energy E_e = 1/2 (R^T x - X)^T K_e (R^T x - X) (energy units, e.g. J).
/// Because R^T x - X has the symmetric displacement gradient S - I and the linear stress
/// commutes with S, f_e is exactly dE_e/dx, and the internal forces have zero net force
/// and zero net torque about any point for every deformation.
///
/// Tangent (TangentKind): simple = R K_e R^T. exact = d f_e / d x
///     = R K_e R^T + R (Z + K_e Y) W,
/// where W (3x12) maps dx to the axial vector w of R^T dR (column 3a + c is
/// (tr(S) I - S)^{-1} (g_a x r_c), r_c = row c of R, see rotationDifferential()),
/// Z (12x3) has the blocks -[(K_e v)_b]x, v = R^T x - X, and Y (12x3) the blocks
/// [(R^T x)_b]x (b = vertex, [p]x the cross-product matrix). The exact element matrix
/// is symmetrised, 1/2 (K + K^T), which changes it only by rounding (and where the
/// pair-sum clamp of rotationDifferential() acts), so symmetric solvers see a
/// symmetric matrix.
///
/// Evaluation runs in two parallel (OpenMP) passes and needs no allocation after the
/// first call:
///   1. per element (four at a time with the default ElementKernel::batched): F = I + sum_a u_a g_a^T, R by
///   polarRotation() (Newton on SO(3),
///      SVD fallback), the corotated strain eps = sym(R^T F) - I, the stress times volume
///      V sigma = V (lambda tr(eps) I + 2 mu eps), the force f_a = R (V sigma) g_a (equal to
///      R K_e (R^T x - X) since K_e v = V sigma g_a), the energy
///      V (mu eps:eps + lambda/2 tr(eps)^2) and the rotated gradients h_a = R g_a;
///   2. per vertex (a column block of K, a segment of f): the sum over the vertex's
///      elements, in ascending element order, of f_a and of the simple tangent blocks
///      R K_ab R^T = V (lambda h_a h_b^T + mu h_b h_a^T + mu (h_a . h_b) I), written
///      through scatter offsets precomputed into the assembler's fixed pattern.
/// Each vertex owns its column block, so the passes need no colouring or atomics and the
/// results are bit-identical for any thread count. The exact tangent is assembled element
/// by element through the MatrixAssembler (it needs the full 12x12 matrix).
///
/// The pass-1 quantities of the last evaluation are cached together with a copy of its
/// displacement: an evaluation (forces, tangent, both, or elasticEnergy()) at a
/// displacement bit-identical to the cached one (compared with memcmp, 8 bytes per DOF)
/// skips pass 1. So elasticEnergy(u) right after forcesAndTangent(u), or before it, costs
/// only the comparison, and energyOfLastEvaluation() returns the energy without taking a
/// displacement at all.
class CorotationalLinearFEM final : public ForceModel {
 public:
  /// Copies mesh's rest positions and connectivity, caches every element's K_e and
  /// shape-function gradients, and builds its own MatrixAssembler. Throws
  /// ValidationError naming the lowest degenerate element (|V| <= 1e-14 L^3 with L its
  /// longest edge, or non-finite); inverted rest elements are accepted (|V| is used).
  explicit CorotationalLinearFEM(const TetMesh& mesh, TangentKind tangentKind = TangentKind::simple);
  /// Same, sharing an assembler built for mesh (e.g. with the mass matrix), so all
  /// matrices have one pattern. Throws asyncfem::Error if assembler is null or was built
  /// for a different number of vertices or elements.
  CorotationalLinearFEM(const TetMesh& mesh, std::shared_ptr<const MatrixAssembler> assembler,
                        TangentKind tangentKind = TangentKind::simple);

  int numDofs() const override { return numDofs_; }
  int numElements() const { return static_cast<int>(elements_.cols()); }
  bool isLinear() const override { return false; }

  TangentKind tangentKind() const { return tangentKind_; }
  void setTangentKind(TangentKind kind) { tangentKind_ = kind; }
  ElementKernel elementKernel() const { return elementKernel_; }
  /// Selects the pass-1 kernel (see ElementKernel); invalidates the cache.
  void setElementKernel(ElementKernel kernel) {
    elementKernel_ = kernel;
    cacheValid_ = false;
  }
  RotationStart rotationStart() const { return rotationStart_; }
  /// Changes where the rotation iterations start (see RotationStart); invalidates the cache.
  void setRotationStart(RotationStart start) {
    rotationStart_ = start;
    cacheValid_ = false;
  }

  /// A 3n x 3n zero matrix in the assembler's pattern.
  Eigen::SparseMatrix<double> createStiffnessMatrix() const override;
  /// forces = f_int(u) = sum_e R_e K_e (R_e^T x_e - X_e), size 3n; displacement is u
  /// (3n, length units). Throws asyncfem::Error on a size mismatch.
  void internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) override;
  /// stiffness = sum_e of the element tangents of tangentKind() (3n x 3n). If stiffness
  /// does not have the assembler's size and entry count it is replaced by
  /// createStiffnessMatrix() first; otherwise only its values are written.
  void tangentStiffness(const Eigen::VectorXd& displacement, Eigen::SparseMatrix<double>& stiffness) override;
  /// Both, with one polar decomposition per element.
  void forcesAndTangent(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces,
                        Eigen::SparseMatrix<double>& stiffness) override;
  /// sum_e 1/2 (R_e^T x_e - X_e)^T K_e (R_e^T x_e - X_e); summed in element order, so
  /// independent of the thread count. Free when displacement is bit-identical to that of
  /// the last evaluation (see the class comment); otherwise one pass over the elements
  /// whose rotations a following evaluation at the same displacement reuses.
  double elasticEnergy(const Eigen::VectorXd& displacement) override;
  /// True once any evaluation has run (then the two accessors below are valid).
  bool hasLastEvaluation() const { return cacheValid_; }
  /// Elastic energy at the displacement of the last evaluation (forces, tangent, both or
  /// energy), computed by it at no extra cost. Throws asyncfem::Error before any
  /// evaluation.
  double energyOfLastEvaluation() const;
  /// The displacement (3n) the last evaluation was made at, a copy (empty before any).
  const Eigen::VectorXd& displacementOfLastEvaluation() const { return cachedDisplacement_; }
  /// Counters of the rotation extractions (Newton steps, SVD fallbacks, cache reuses).
  const RotationStats& rotationStats() const { return rotationStats_; }
  /// Element e's tangent of tangentKind() at displacement (its own polar decomposition,
  /// independent of the cached rotations), equal to its contribution to
  /// tangentStiffness(). Throws asyncfem::Error on a size mismatch or an element out of
  /// range.
  bool elementTangent(const Eigen::VectorXd& displacement, int element, ElementMatrix& tangent) const override;

  /// Element rotations R_e (numElements 3x3 matrices, det +1) of the last evaluation
  /// (any of the four functions above, elementTangent() excepted); identities before the
  /// first one.
  const std::vector<Eigen::Matrix3d>& rotations() const { return rotations_; }
  /// The cached linear stiffness K_e of element e (12x12).
  const ElementMatrix& elementStiffness(int e) const { return elementStiffness_[static_cast<std::size_t>(e)]; }
  const MatrixAssembler& assembler() const { return *assembler_; }
  const std::shared_ptr<const MatrixAssembler>& sharedAssembler() const { return assembler_; }

 private:
  void checkDisplacement(const Eigen::VectorXd& displacement, const char* caller) const;
  // Positions of element e's vertices, x = X + u (3x4).
  ElementPositions currentPositions(int e, const Eigen::VectorXd& displacement) const;
  // Pass 1 (see the class comment) unless the cache already holds displacement; stores
  // R, h, element forces and energies (and, for the exact tangent, (tr S I - S)^{-1}).
  void evaluateElements(const Eigen::VectorXd& displacement, bool needDifferentialOperator);
  // Pass 1 for element e with the scalar kernel.
  void evaluateElement(int e, const Eigen::VectorXd& displacement, bool warmStart, bool needDifferentialOperator,
                       long long& newtonSteps, long long& fallbacks);
  // Pass 1 for the first numElements - numElements % 4 elements with the batched kernel.
  void evaluateBatches(const Eigen::VectorXd& displacement, bool needDifferentialOperator, long long& newtonSteps,
                       long long& fallbacks);
  bool cacheHolds(const Eigen::VectorXd& displacement) const;
  void assembleForces(Eigen::VectorXd& forces) const;
  void assembleTangent(const Eigen::VectorXd& displacement, Eigen::SparseMatrix<double>& stiffness) const;
  void assembleSimpleTangent(Eigen::SparseMatrix<double>& stiffness) const;

  std::shared_ptr<const MatrixAssembler> assembler_;
  TangentKind tangentKind_;
  int numDofs_ = 0;
  Eigen::Matrix4Xi elements_;
  std::vector<ElementPositions> restPositions_;                // X per element (3x4)
  std::vector<Eigen::Matrix<double, 3, 4>> shapeGradients_;    // g_a per element (3x4)
  std::vector<ElementMatrix> elementStiffness_;                // K_e
  std::vector<Eigen::Matrix3d> rotations_;                     // R_e of the last evaluation
  std::vector<Eigen::Matrix3d> differentialOperators_;         // (tr S I - S)^{-1}, exact tangent only
  std::vector<double> elementEnergies_;                        // E_e of the last evaluation
  std::vector<Eigen::Vector2d> lameVolume_;                    // (lambda V, mu V) per element
  std::vector<Eigen::Matrix<double, 3, 4>> rotatedGradients_;  // h_a = R g_a of the last evaluation
  std::vector<Eigen::Matrix<double, 3, 4>> elementForces_;     // f_e of the last evaluation (3x4)
  // Vertex -> incident (element, local vertex) pairs, encoded 4 e + b, ascending in e.
  std::vector<int> incidenceOffsets_, incidences_;
  // valuePtr() index of entry (3 a, 3 b) of element e at 16 e + 4 b + a, and the column
  // length (stride between the three columns of vertex b) at 4 e + b.
  std::vector<int> blockSlots_, columnLengths_;
  std::vector<int> patternOuter_;                          // outer index array of the assembler's pattern
  std::shared_ptr<const detail::ElementBatches> batches_;  // geometry of the batched kernel
  ElementKernel elementKernel_ = ElementKernel::batched;
  RotationStart rotationStart_ = RotationStart::fromDeformation;
  RotationStats rotationStats_;
  Eigen::VectorXd cachedDisplacement_;
  bool cacheValid_ = false;
  bool cacheHasDifferentialOperators_ = false;
  double cachedEnergy_ = 0.0;
};

}  // namespace asyncfem
