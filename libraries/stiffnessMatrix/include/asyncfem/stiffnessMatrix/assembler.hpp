// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <functional>
#include <vector>

namespace asyncfem {

/// Sparsity pattern of the 3n x 3n matrices of a tet mesh (full storage, both triangles,
/// column-major, int indices, sorted row indices) computed once, plus an element -> value
/// slot map: slot(e, i, j) is the index into valuePtr() where entry (i, j) of element e's
/// 12x12 matrix goes. Re-assembly (corotational FEM, new materials, new timestep) then
/// touches values only, and every matrix built by one assembler shares one pattern, so
/// linear combinations such as M + h D + h^2 K are value-wise sums (see combine()).
///
/// Assembly is parallel (OpenMP) and deterministic: no floating-point atomics; the
/// result is bit-identical for any thread count.
class MatrixAssembler {
public:
  explicit MatrixAssembler(const TetMesh& mesh);

  int numDofs() const { return numDofs_; }
  int numElements() const { return numElements_; }
  /// A matrix with the pattern and all values zero.
  Eigen::SparseMatrix<double> createMatrix() const;
  /// Number of stored entries (both triangles).
  Eigen::Index nonZeros() const;
  /// Index into valuePtr() of local entry (i, j) of element e, i, j in [0, 12).
  int slot(int e, int i, int j) const { return slots_[(static_cast<std::size_t>(e) * 144) + (i * 12) + j]; }

  /// Computes one element's 12x12 matrix; called concurrently for different elements.
  using ElementMatrixFunction = std::function<void(int element, ElementMatrix& out)>;
  /// Sets matrix's values to sum_e (element matrix of e) scattered through the slot
  /// map. matrix must have this assembler's pattern (from createMatrix()).
  void assemble(const ElementMatrixFunction& elementMatrix, Eigen::SparseMatrix<double>& matrix) const;
  /// Same, with element matrices already computed (one per element).
  void assemble(const std::vector<ElementMatrix>& elementMatrices, Eigen::SparseMatrix<double>& matrix) const;

  /// Computes one element's 12-vector; called concurrently.
  using ElementVectorFunction = std::function<void(int element, ElementVector& out)>;
  /// Returns the 3n vector sum_e (element vector of e) scattered to global DOFs.
  Eigen::VectorXd assembleVector(const ElementVectorFunction& elementVector) const;

private:
  int numDofs_ = 0;
  int numElements_ = 0;
  Eigen::Matrix4Xi elements_;
  Eigen::SparseMatrix<double> pattern_;
  std::vector<int> slots_;  // numElements * 144
  // Private scheduling data (e.g. element colouring) lives here.
  std::vector<int> colorOffsets_;
  std::vector<int> coloredElements_;
};

/// Linear FEM stiffness K (3n x 3n) of the mesh with its per-element materials.
Eigen::SparseMatrix<double> linearStiffnessMatrix(const TetMesh& mesh, const MatrixAssembler& assembler);

enum class MassType { consistent, lumped };
/// Mass matrix M (3n x 3n) in the assembler's pattern (lumped: only diagonal values
/// non-zero, pattern unchanged). Sums to rho V per coordinate.
Eigen::SparseMatrix<double> massMatrix(const TetMesh& mesh, const MatrixAssembler& assembler, MassType type);

/// Rayleigh damping D = alpha M + beta K (M and K must share a pattern).
Eigen::SparseMatrix<double> rayleighDamping(const Eigen::SparseMatrix<double>& mass,
                                            const Eigen::SparseMatrix<double>& stiffness, double alpha,
                                            double beta);

/// out = sum_i coefficients[i] * matrices[i], all sharing one pattern (checked:
/// asyncfem::Error if the patterns differ). out gets the same pattern.
void combine(const std::vector<double>& coefficients, const std::vector<const Eigen::SparseMatrix<double>*>& matrices,
             Eigen::SparseMatrix<double>& out);

}  // namespace asyncfem
