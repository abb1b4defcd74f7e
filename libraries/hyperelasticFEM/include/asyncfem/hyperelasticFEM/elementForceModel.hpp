// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/forceModel/forceModel.hpp>
#include <asyncfem/hyperelasticFEM/tetElementGeometry.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <memory>
#include <string>
#include <vector>

namespace asyncfem {

/// Shared machinery of the hyperelastic force models: a ForceModel whose energy, forces
/// and tangent are sums over tetrahedra of terms that depend on the element's
/// deformation gradient F only. Derived classes supply computeElement(); this class
/// runs the element loops (OpenMP, static schedule), scatters and checks the results.
///
/// Determinism and allocation: element forces and energies go to per-element scratch
/// kept by the model (allocated at construction) and are summed serially in element
/// order, the tangent goes through the MatrixAssembler's coloured assembly into its fixed
/// pattern; results are bit-identical for any thread count and no evaluation allocates
/// once the output vector and matrix have their size and pattern. One virtual call per
/// element selects the material; it costs nothing measurable next to the element work
/// (an SVD or a 12x12 product, see the benchmark).
///
/// Failure: a non-finite element energy, force or tangent (e.g. neo-Hookean log J of a
/// flattened element with inversion handling off) throws NumericalError naming the lowest
/// such element and its J = det F.
class ElementForceModel : public ForceModel {
 public:
  int numDofs() const override { return geometry_.numDofs; }
  int numElements() const { return geometry_.numElements(); }
  bool isLinear() const override { return false; }

  /// A 3n x 3n zero matrix in the assembler's pattern.
  Eigen::SparseMatrix<double> createStiffnessMatrix() const override;
  /// forces = f_int(u) = dE/du (3n, force units; Vega's sign: opposes the deformation).
  void internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) override;
  /// stiffness = K(u) = d f_int / du (3n x 3n). If stiffness lacks the assembler's
  /// pattern it is replaced by createStiffnessMatrix() first; otherwise only values are
  /// written.
  void tangentStiffness(const Eigen::VectorXd& displacement, Eigen::SparseMatrix<double>& stiffness) override;
  /// Both in one element pass (one deformation gradient and decomposition per element).
  void forcesAndTangent(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces,
                        Eigen::SparseMatrix<double>& stiffness) override;
  /// E(u) = sum_e |V_e| W(F_e) (energy units), summed in element order.
  double elasticEnergy(const Eigen::VectorXd& displacement) override;
  /// Element e's 12x12 tangent at displacement, equal to its contribution to
  /// tangentStiffness(). Throws asyncfem::Error on a size mismatch or bad element index.
  bool elementTangent(const Eigen::VectorXd& displacement, int element, ElementMatrix& tangent) const override;

  /// Energy, force (12) and tangent (12x12) of element e alone at displacement; null
  /// outputs are skipped.
  void elementTerms(const Eigen::VectorXd& displacement, int element, double* energy, ElementVector* force,
                    ElementMatrix* tangent) const;

  const TetElementGeometry& geometry() const { return geometry_; }
  const MatrixAssembler& assembler() const { return *assembler_; }
  const std::shared_ptr<const MatrixAssembler>& sharedAssembler() const { return assembler_; }

 protected:
  /// assembler may be null (one is built for mesh); otherwise it must match mesh.
  ElementForceModel(const TetMesh& mesh, std::shared_ptr<const MatrixAssembler> assembler, const char* name);

  /// Energy |V_e| W(F), force (d/dx_e of it, 12) and tangent (12x12) of element e with
  /// deformation gradient F; each output may be null. Called concurrently for different
  /// elements; must not throw (non-finite results are reported by the caller).
  virtual void computeElement(int element, const Eigen::Matrix3d& deformationGradient, double* energy,
                              ElementVector* force, ElementMatrix* tangent) const = 0;

  /// Forces (when forces is not null) and tangents of the count <= MatrixAssembler::
  /// kElementBatch consecutive elements first, ... with deformation gradients
  /// deformationGradients[0 .. count), into forces[i] and tangents[i]: what count calls of
  /// computeElement() give (the default makes them). A model overrides it to evaluate the
  /// elements together (SIMD lanes over elements); the tangent path of the element loop
  /// calls it. Called concurrently for different batches; must not throw.
  virtual void computeBatch(int first, int count, const Eigen::Matrix3d* deformationGradients, ElementVector* forces,
                            ElementMatrix* tangents) const;

  const std::string& modelName() const { return name_; }

 private:
  void checkDisplacement(const Eigen::VectorXd& displacement, const char* caller) const;
  void ensurePattern(Eigen::SparseMatrix<double>& stiffness) const;
  // Runs the element loop; forces and/or stiffness may be null.
  void evaluate(const Eigen::VectorXd& displacement, Eigen::VectorXd* forces, Eigen::SparseMatrix<double>* stiffness,
                const char* caller);
  [[noreturn]] void reportNonFinite(int element, const Eigen::VectorXd& displacement, const char* what) const;

  std::string name_;
  TetElementGeometry geometry_;
  std::shared_ptr<const MatrixAssembler> assembler_;
  std::vector<ElementVector> elementForces_;  // scratch, numElements
  std::vector<double> elementEnergies_;       // scratch, numElements
};

}  // namespace asyncfem
