// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace asyncfem {

/// Internal elastic forces of a body as a function of its displacement.
///
/// Sign convention (as in Vega FEM): f_int(u) is the force the material exerts
/// *against* the deformation, so the equations of motion read
///     M a + D v + f_int(u) = f_ext.
/// For linear FEM f_int(u) = K u. All vectors are stacked 3n (x0 y0 z0 x1 ...), all
/// matrices 3n x 3n in the pattern of the force model's assembler (full storage).
/// Implementations are called once per (large) step, so one virtual call per step is
/// fine; element loops inside are non-virtual and parallel.
class ForceModel {
 public:
  virtual ~ForceModel() = default;

  virtual int numDofs() const = 0;
  /// True when f_int(u) = K u with a constant K: integrators may then factor once.
  virtual bool isLinear() const = 0;

  /// A matrix with the pattern tangentStiffness() fills (all values zero).
  virtual Eigen::SparseMatrix<double> createStiffnessMatrix() const = 0;
  /// f_int(u), size 3n.
  virtual void internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) = 0;
  /// K(u) = d f_int / d u into stiffness (pattern from createStiffnessMatrix()).
  virtual void tangentStiffness(const Eigen::VectorXd& displacement, Eigen::SparseMatrix<double>& stiffness) = 0;
  /// Both at once; implementations that share work (rotations) override it.
  virtual void forcesAndTangent(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces,
                                Eigen::SparseMatrix<double>& stiffness) {
    internalForces(displacement, forces);
    tangentStiffness(displacement, stiffness);
  }
  /// Elastic potential energy at u (0 at rest).
  virtual double elasticEnergy(const Eigen::VectorXd& displacement) = 0;

  /// The tangent stiffness of one element alone, d f_e / d u_e at displacement (12 x 12,
  /// the DOFs of the element's four vertices in connectivity order), for models that are
  /// sums of per-element terms over the tet mesh they were built for; the entries equal
  /// that element's contribution to tangentStiffness() at the same displacement. Returns
  /// false (the default) when the model has no per-element form. The asynchronous
  /// integrator's stable coupling asks for the interface elements, a few per step, so
  /// implementations need not be fast.
  virtual bool elementTangent(const Eigen::VectorXd& displacement, int element,
                              Eigen::Matrix<double, 12, 12>& tangent) const {
    (void)displacement;
    (void)element;
    (void)tangent;
    return false;
  }
  /// elementTangent() for meshes of either element kind: 12 x 12 on tetrahedra, 24 x 24 on
  /// hexahedra (the DOFs of the element's vertices in connectivity order), with the same
  /// meaning and return value. The default forwards to elementTangent(); models on
  /// hexahedral meshes override it.
  virtual bool elementTangentOfAnyKind(const Eigen::VectorXd& displacement, int element,
                                       Eigen::MatrixXd& tangent) const {
    Eigen::Matrix<double, 12, 12> fixed;
    if (!elementTangent(displacement, element, fixed)) return false;
    tangent = fixed;
    return true;
  }
};

}  // namespace asyncfem
