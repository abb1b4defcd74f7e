// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/forceModel/forceModel.hpp>
#include <asyncfem/hexElements/hexElementMatrices.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <string>
#include <vector>

namespace asyncfem {

/// What the force models on hexahedral meshes share: f_int(u) = sum_e f_e, K(u) = sum_e K_e
/// and the energy, the sum of the elements', from a per-element kernel (element()). The
/// stiffness pattern is fixed at construction (every 3 x 3 block of every element, also
/// where a value is zero), so integrators may keep a symbolic factorization. The element
/// loop is serial. Throws ValidationError on a tetrahedral mesh.
class HexForceModel : public ForceModel {
 public:
  int numDofs() const override { return numDofs_; }
  Eigen::SparseMatrix<double> createStiffnessMatrix() const override { return pattern_; }
  void internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) override;
  void tangentStiffness(const Eigen::VectorXd& displacement, Eigen::SparseMatrix<double>& stiffness) override;
  void forcesAndTangent(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces,
                        Eigen::SparseMatrix<double>& stiffness) override;
  double elasticEnergy(const Eigen::VectorXd& displacement) override;

 protected:
  /// name: the model's class name, for messages.
  HexForceModel(const TetMesh& mesh, std::string name);
  /// Element e with its rest and deformed positions; tangent only when withTangent.
  virtual HexElementEnergy element(Eigen::Index e, const HexElementPositions& rest, const HexElementPositions& deformed,
                                   bool withTangent) const = 0;
  const std::string& name() const { return name_; }

 private:
  /// Evaluates every element at displacement; adds forces (when not null) and the tangent
  /// (when not null, into the pattern) and returns the energy.
  double evaluate(const Eigen::VectorXd& displacement, Eigen::VectorXd* forces,
                  Eigen::SparseMatrix<double>* stiffness) const;
  void checkDisplacement(const Eigen::VectorXd& displacement, const char* what) const;

  std::string name_;
  int numDofs_ = 0;
  Eigen::Matrix3Xd restPositions_;
  Eigen::Matrix<int, 8, Eigen::Dynamic> hexahedra_;
  Eigen::SparseMatrix<double> pattern_;
  /// Per element, 8 x 8 value indices of block (a, b)'s entry (3 a, 3 b) in pattern_;
  /// entry (3 a + i, 3 b + j) is at slot + j * columnLength_[vertex b] + i.
  std::vector<Eigen::Matrix<int, 8, 8>> blockSlots_;
  std::vector<int> columnLength_;  ///< per vertex: entries of each of its three columns
};

}  // namespace asyncfem
