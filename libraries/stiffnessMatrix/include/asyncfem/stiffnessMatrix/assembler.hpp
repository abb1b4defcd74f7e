// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <functional>
#include <vector>

namespace asyncfem {

/// Consistent (rho V / 20 (1 + delta_ab)) or row-sum lumped (rho V / 4) element mass.
enum class MassType { consistent, lumped };

/// Sparsity pattern of the 3n x 3n matrices of a tet mesh (full storage, both triangles,
/// column-major, int indices, sorted row indices) computed once, plus an element -> value
/// slot map: slot(e, i, j) is the index into valuePtr() where entry (i, j) of element e's
/// 12x12 matrix goes. Re-assembly (corotational FEM, new materials, new timestep) then
/// touches values only, and every matrix built by one assembler shares one pattern, so
/// linear combinations such as M + h D + h^2 K are value-wise sums (see combine()).
///
/// Assembly is parallel (OpenMP) and deterministic: no floating-point atomics; the
/// result is bit-identical for any thread count. Chunks of consecutive elements are
/// coloured greedily so that chunks of one colour share no vertex; colours run in order,
/// the chunks of a colour in parallel, so every entry sums its contributions in one
/// fixed order.
///
/// The pattern couples the three DOFs of vertices u and v when an element contains both,
/// and always holds the 3x3 diagonal block of every vertex (also of vertices no element
/// uses), so the diagonal is structurally complete. Memory: 16 ints per element for the
/// slot map plus the element and vertex-block arrays (about 85 MB for 1M tets); the
/// scalar pattern is only materialised in the matrices themselves.
class MatrixAssembler {
 public:
  /// Builds the pattern, slot map and colouring of mesh's connectivity (O(elements),
  /// parallel). Throws asyncfem::Error if the pattern needs more than INT_MAX entries.
  explicit MatrixAssembler(const TetMesh& mesh);

  int numDofs() const { return numDofs_; }
  int numElements() const { return numElements_; }
  /// A matrix with the pattern and all values zero.
  Eigen::SparseMatrix<double> createMatrix() const;
  /// Number of stored entries (both triangles).
  Eigen::Index nonZeros() const;
  /// Index into valuePtr() of local entry (i, j) of element e, i, j in [0, 12).
  ///
  /// Only one slot per vertex pair is stored (16 per element): the three columns of a
  /// vertex share one row pattern and the three rows of a vertex are consecutive, so
  /// entry (3a + ci, 3b + cj) lies ci entries below the stored block slot of (a, b) and
  /// cj times the length of vertex b's columns further on.
  int slot(int e, int i, int j) const {
    const int a = i / 3;
    const int b = j / 3;
    const int columnVertex = elements_(b, e);
    const auto v = static_cast<std::size_t>(columnVertex);
    const int columnLength = 3 * (blockOuter_[v + 1] - blockOuter_[v]);
    return blockSlots_[(static_cast<std::size_t>(e) * 16) + static_cast<std::size_t>((b * 4) + a)] + (i - (3 * a)) +
           ((j - (3 * b)) * columnLength);
  }
  /// Number of element groups processed one after another during assembly (elements of
  /// one group share no vertex with each other group of the same colour).
  int numColors() const { return static_cast<int>(colorOffsets_.size()) - 1; }
  /// Elements per group (consecutive element ids) used by the scheduling.
  int elementsPerChunk() const { return chunkSize_; }

  /// Computes one element's 12x12 matrix; called concurrently for different elements.
  using ElementMatrixFunction = std::function<void(int element, ElementMatrix& out)>;
  /// Sets matrix's values to sum_e (element matrix of e) scattered through the slot
  /// map. matrix must have this assembler's pattern (from createMatrix(); checked:
  /// asyncfem::Error). If elementMatrix throws, every element is still visited and the
  /// exception of the lowest failing element is rethrown (matrix values are then
  /// unspecified). The std::function call per element costs no measurable time next to
  /// the element computation (see the benchmark), so there is no template overload.
  void assemble(const ElementMatrixFunction& elementMatrix, Eigen::SparseMatrix<double>& matrix) const;
  /// Most elements one ElementBatchFunction call computes (kElementBatch consecutive ids).
  static constexpr int kElementBatch = 4;
  /// Computes the 12x12 matrices of elements first, ..., first + count - 1 (count in
  /// [1, kElementBatch], consecutive ids) into out[0 .. count); called concurrently for
  /// different batches. Lets a caller evaluate several elements at once (SIMD lanes over
  /// elements) while the scatter stays the deterministic one of assemble().
  using ElementBatchFunction = std::function<void(int first, int count, ElementMatrix* out)>;
  /// Same as assemble(), with the element matrices computed in batches of up to
  /// kElementBatch consecutive elements of one chunk (a batch is shorter only at a chunk's
  /// end). The sum is bit-identical to assemble() with the same element matrices. If a
  /// batch throws, none of its elements is scattered and the exception of the lowest
  /// failing batch (by its first element) is rethrown after every batch was visited.
  void assembleBatches(const ElementBatchFunction& elementBatch, Eigen::SparseMatrix<double>& matrix) const;
  /// Same, with element matrices already computed (numElements of them; asyncfem::Error
  /// otherwise).
  void assemble(const std::vector<ElementMatrix>& elementMatrices, Eigen::SparseMatrix<double>& matrix) const;

  /// Computes one element's 12-vector; called concurrently.
  using ElementVectorFunction = std::function<void(int element, ElementVector& out)>;
  /// Returns the 3n vector sum_e (element vector of e) scattered to global DOFs,
  /// deterministic like assemble().
  Eigen::VectorXd assembleVector(const ElementVectorFunction& elementVector) const;

 private:
  friend void assembleLinearStiffness(const TetMesh& mesh, const MatrixAssembler& assembler,
                                      Eigen::SparseMatrix<double>& stiffness);
  friend Eigen::SparseMatrix<double> massMatrix(const TetMesh& mesh, const MatrixAssembler& assembler, MassType type);
  // Scatter-adds callback(e, Ke) for every element in the deterministic colour order;
  // defined (and instantiated) in assembler.cpp only, so callers need no OpenMP flags.
  template <class ElementFunction>
  void assembleWith(const ElementFunction& elementMatrix, Eigen::SparseMatrix<double>& matrix) const;
  // The scatter of one element matrix into matrix's values (slot map of element e).
  void scatterElement(int e, const ElementMatrix& local, double* values) const;
  void checkPattern(const Eigen::SparseMatrix<double>& matrix, const char* caller) const;

  int numDofs_ = 0;
  int numElements_ = 0;
  int chunkSize_ = 1;
  Eigen::Matrix4Xi elements_;
  // Vertex-block pattern, CSR by column vertex: the row vertices of column vertex v are
  // blockRows_[blockOuter_[v] .. blockOuter_[v+1]), ascending. The scalar pattern
  // (3x3 dense blocks) follows from it, so it is not stored here.
  std::vector<int> blockOuter_;
  std::vector<int> blockRows_;
  // numElements * 16: valuePtr() index of entry (3 va, 3 vb) for the element's vertex
  // pair (a, b), at e * 16 + b * 4 + a.
  std::vector<int> blockSlots_;
  // Elements are grouped in chunks of chunkSize_ consecutive ids; chunks are coloured so
  // that chunks of one colour share no vertex. Colour c holds the chunks
  // coloredChunks_[colorOffsets_[c] .. colorOffsets_[c+1]).
  std::vector<int> colorOffsets_;
  std::vector<int> coloredChunks_;
};

/// Linear FEM stiffness K (3n x 3n, units of E times length, e.g. N/m) of the mesh with
/// its per-element materials: K = sum_e V_e B_e^T C_e B_e. Throws ValidationError naming
/// the lowest degenerate element (|V| <= 1e-14 L^3, L its longest edge); inverted
/// elements are accepted (|V| is used).
Eigen::SparseMatrix<double> linearStiffnessMatrix(const TetMesh& mesh, const MatrixAssembler& assembler);
/// Same as linearStiffnessMatrix, re-assembling into stiffness (from createMatrix()), so
/// that new materials cost one value pass and no allocation.
void assembleLinearStiffness(const TetMesh& mesh, const MatrixAssembler& assembler,
                             Eigen::SparseMatrix<double>& stiffness);

/// Mass matrix M (3n x 3n, mass units, e.g. kg) in the assembler's pattern (lumped:
/// only diagonal values non-zero, pattern unchanged). Sums to rho V per coordinate:
/// 1_x^T M 1_x = sum_e rho_e |V_e|. Throws ValidationError naming the lowest degenerate
/// element.
Eigen::SparseMatrix<double> massMatrix(const TetMesh& mesh, const MatrixAssembler& assembler, MassType type);

/// Rayleigh damping D = alpha M + beta K (M and K must share a pattern; asyncfem::Error
/// otherwise). alpha in 1/s, beta in s.
Eigen::SparseMatrix<double> rayleighDamping(const Eigen::SparseMatrix<double>& mass,
                                            const Eigen::SparseMatrix<double>& stiffness, double alpha, double beta);

/// out = sum_i coefficients[i] * matrices[i], all sharing one pattern (checked by
/// comparing outer and inner index arrays: asyncfem::Error naming the first matrix that
/// differs, or a count mismatch). out gets the same pattern (allocated only if it does not
/// have it yet) and may be one of the inputs. Parallel, value-wise, deterministic.
void combine(const std::vector<double>& coefficients, const std::vector<const Eigen::SparseMatrix<double>*>& matrices,
             Eigen::SparseMatrix<double>& out);

}  // namespace asyncfem
