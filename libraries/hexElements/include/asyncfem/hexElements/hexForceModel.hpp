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
/// loop runs the colours of a greedy vertex-sharing colouring in order and the elements of
/// one colour on OpenMP threads (from 2048 elements on), so element() must be safe to call
/// concurrently; every entry is summed in the same order on any number of threads. An
/// element() that throws stops the evaluation with the lowest-numbered failing element's
/// error. Throws ValidationError on a tetrahedral mesh.
class HexForceModel : public ForceModel {
 public:
  int numDofs() const override { return numDofs_; }
  Eigen::SparseMatrix<double> createStiffnessMatrix() const override { return pattern_; }
  void internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) override;
  void tangentStiffness(const Eigen::VectorXd& displacement, Eigen::SparseMatrix<double>& stiffness) override;
  void forcesAndTangent(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces,
                        Eigen::SparseMatrix<double>& stiffness) override;
  double elasticEnergy(const Eigen::VectorXd& displacement) override;
  /// The 24 x 24 tangent of hexahedron e alone at displacement, as element() gives it (the
  /// same entries the assembled tangent sums). Always available.
  bool elementTangentOfAnyKind(const Eigen::VectorXd& displacement, int e, Eigen::MatrixXd& tangent) const override {
    HexElementPositions rest, deformed;
    for (int a = 0; a < 8; ++a) {
      const int v = hexahedra_(a, e);
      rest.col(a) = restPositions_.col(v);
      deformed.col(a) = rest.col(a) + displacement.segment<3>(3 * static_cast<Eigen::Index>(v));
    }
    tangent = element(e, rest, deformed, true).tangent;
    return true;
  }

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
  /// Adds element e's forces and tangent into forces and stiffness (either may be null).
  void scatter(Eigen::Index e, const HexElementEnergy& result, Eigen::VectorXd* forces,
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
  /// Elements grouped by colour (elements of one colour share no vertex): colour c holds
  /// coloredElements_[colorOffsets_[c] .. colorOffsets_[c + 1]).
  std::vector<int> coloredElements_;
  std::vector<int> colorOffsets_;
};

}  // namespace asyncfem
