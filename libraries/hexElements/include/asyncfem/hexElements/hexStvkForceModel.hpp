// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/forceModel/forceModel.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

namespace asyncfem {

/// Saint Venant-Kirchhoff FEM on a hexahedral mesh (the Green-strain form of hexStvk,
/// 2 x 2 x 2 Gauss points per element): f_int(u) = sum_e f_e, K(u) = sum_e K_e, the energy
/// the sum of the elements'. The tangent is the exact derivative of the forces. The
/// stiffness pattern is fixed at construction (every 3 x 3 block of every element, also
/// where a value is zero), so integrators may keep a symbolic factorization.
///
/// No inversion handling (StVK's energy softens under strong compression, as Vega's
/// StVKForceModel); the element loop is serial. Throws ValidationError on a tetrahedral
/// mesh and, naming the element, for a rest shape with det J <= 0 at a Gauss point.
class HexStvkForceModel : public ForceModel {
 public:
  explicit HexStvkForceModel(const TetMesh& mesh);

  int numDofs() const override { return numDofs_; }
  bool isLinear() const override { return false; }
  Eigen::SparseMatrix<double> createStiffnessMatrix() const override { return pattern_; }
  void internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) override;
  void tangentStiffness(const Eigen::VectorXd& displacement, Eigen::SparseMatrix<double>& stiffness) override;
  void forcesAndTangent(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces,
                        Eigen::SparseMatrix<double>& stiffness) override;
  double elasticEnergy(const Eigen::VectorXd& displacement) override;

 private:
  /// Evaluates every element at displacement; adds forces (when not null) and the tangent
  /// (when not null, into the pattern) and returns the energy.
  double evaluate(const Eigen::VectorXd& displacement, Eigen::VectorXd* forces,
                  Eigen::SparseMatrix<double>* stiffness) const;
  void checkDisplacement(const Eigen::VectorXd& displacement, const char* what) const;

  int numDofs_ = 0;
  Eigen::Matrix3Xd restPositions_;
  Eigen::Matrix<int, 8, Eigen::Dynamic> hexahedra_;
  std::vector<Eigen::Vector2d> youngAndPoisson_;  ///< per element
  Eigen::SparseMatrix<double> pattern_;
  /// Per element, 8 x 8 value indices of block (a, b)'s entry (3 a, 3 b) in pattern_;
  /// entry (3 a + i, 3 b + j) is at slot + j * columnLength_[vertex b] + i.
  std::vector<Eigen::Matrix<int, 8, 8>> blockSlots_;
  std::vector<int> columnLength_;  ///< per vertex: entries of each of its three columns
};

}  // namespace asyncfem
