// SPDX-License-Identifier: BSD-3-Clause
#include <mpi.h>
#include <petscsys.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/petscBackend/problemSettings.hpp>
#include <asyncfem/petscBackend/rankSummedForceModel.hpp>
#include <string>
#include <utility>
#include <vector>

#include "detail/distributedLayout.hpp"
#include "detail/petscCall.hpp"
#include "detail/subMeshModel.hpp"

namespace asyncfem {

namespace {

class RankSummedForceModel final : public ForceModel {
 public:
  RankSummedForceModel(const TetMesh& mesh, const ProblemSettings& physics, std::shared_ptr<ForceModel> wholeMesh)
      : whole_(std::move(wholeMesh)) {
    const std::vector<int> parts = detail::elementPartsOnEveryRank(mesh, PETSC_COMM_WORLD);
    int rank = 0;
    MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
    for (int e = 0; e < mesh.numElements(); ++e) {
      if (parts[static_cast<std::size_t>(e)] == rank) meshElement_.push_back(e);
    }
    const Eigen::SparseMatrix<double> pattern = whole_->createStiffnessMatrix();
    entries_ = pattern.nonZeros();
    detail::collectively(PETSC_COMM_WORLD, [&] {
      if (meshElement_.empty()) return;  // a rank without elements adds zeros
      const TetMesh part = detail::subMesh(mesh, meshElement_, meshVertex_);
      detail::inMeshNumbering(meshElement_, [&] {
        model_ = detail::makeSubMeshModel(part, petscForceModelKind(physics.forceModel), physics.tangent,
                                          physics.hyperelastic);
      });
      subTangent_ = model_->createStiffnessMatrix();
      mapEntries(pattern);
      subDisplacement_.setZero(part.numDofs());
    });
  }

  int numDofs() const override { return whole_->numDofs(); }
  bool isLinear() const override { return whole_->isLinear(); }
  Eigen::SparseMatrix<double> createStiffnessMatrix() const override { return whole_->createStiffnessMatrix(); }
  void internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) override {
    whole_->internalForces(displacement, forces);
  }
  void tangentStiffness(const Eigen::VectorXd& displacement, Eigen::SparseMatrix<double>& stiffness) override {
    whole_->tangentStiffness(displacement, stiffness);
  }
  double elasticEnergy(const Eigen::VectorXd& displacement) override { return whole_->elasticEnergy(displacement); }
  bool elementTangent(const Eigen::VectorXd& displacement, int element,
                      Eigen::Matrix<double, 12, 12>& tangent) const override {
    return whole_->elementTangent(displacement, element, tangent);
  }
  bool elementTangentOfAnyKind(const Eigen::VectorXd& displacement, int element,
                               Eigen::MatrixXd& tangent) const override {
    return whole_->elementTangentOfAnyKind(displacement, element, tangent);
  }

  // This rank's elements through the sub-mesh model, scattered into the whole mesh's
  // vector and pattern, then summed over the ranks.
  void forcesAndTangent(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces,
                        Eigen::SparseMatrix<double>& stiffness) override {
    detail::collectively(PETSC_COMM_WORLD, [&] {
      if (displacement.size() != numDofs()) {
        throw Error("rank-summed force model: displacement has size " + std::to_string(displacement.size()) +
                    ", expected " + std::to_string(numDofs()));
      }
      if (stiffness.rows() != numDofs() || stiffness.cols() != numDofs() || !stiffness.isCompressed() ||
          stiffness.nonZeros() != entries_) {
        stiffness = createStiffnessMatrix();  // not the pattern of createStiffnessMatrix(): given it, as the models do
      }
      forces.setZero(numDofs());
      std::fill(stiffness.valuePtr(), stiffness.valuePtr() + stiffness.nonZeros(), 0.0);
      if (!model_) return;
      for (std::size_t i = 0; i < meshVertex_.size(); ++i) {
        subDisplacement_.segment<3>(3 * static_cast<Eigen::Index>(i)) = displacement.segment<3>(3 * meshVertex_[i]);
      }
      detail::inMeshNumbering(meshElement_,
                              [&] { model_->forcesAndTangent(subDisplacement_, subForces_, subTangent_); });
      for (std::size_t i = 0; i < meshVertex_.size(); ++i) {
        forces.segment<3>(3 * meshVertex_[i]) += subForces_.segment<3>(3 * static_cast<Eigen::Index>(i));
      }
      double* values = stiffness.valuePtr();
      const double* subValues = subTangent_.valuePtr();
      for (std::size_t p = 0; p < entry_.size(); ++p) values[entry_[p]] += subValues[p];
    });
    detail::sumOverRanks(PETSC_COMM_WORLD, forces.data(), static_cast<std::size_t>(forces.size()));
    detail::sumOverRanks(PETSC_COMM_WORLD, stiffness.valuePtr(), static_cast<std::size_t>(stiffness.nonZeros()));
  }

 private:
  // entry_[p]: the stored entry of the whole mesh's pattern that the sub-tangent's stored
  // entry p adds to (same DOF pair in mesh numbering).
  void mapEntries(const Eigen::SparseMatrix<double>& pattern) {
    entry_.resize(static_cast<std::size_t>(subTangent_.nonZeros()));
    for (Eigen::Index j = 0; j < subTangent_.outerSize(); ++j) {
      const Eigen::Index column = (3 * meshVertex_[static_cast<std::size_t>(j / 3)]) + (j % 3);
      const int* rowsBegin = pattern.innerIndexPtr() + pattern.outerIndexPtr()[column];
      const int* rowsEnd = pattern.innerIndexPtr() + pattern.outerIndexPtr()[column + 1];
      for (Eigen::Index p = subTangent_.outerIndexPtr()[j]; p < subTangent_.outerIndexPtr()[j + 1]; ++p) {
        const int subRow = subTangent_.innerIndexPtr()[p];
        const int row = (3 * meshVertex_[static_cast<std::size_t>(subRow / 3)]) + (subRow % 3);
        const int* found = std::lower_bound(rowsBegin, rowsEnd, row);
        if (found == rowsEnd || *found != row) {
          throw Error("rank-summed force model: the whole mesh's stiffness pattern lacks entry (" +
                      std::to_string(row) + ", " + std::to_string(column) + ")");
        }
        entry_[static_cast<std::size_t>(p)] = found - pattern.innerIndexPtr();
      }
    }
  }

  std::shared_ptr<ForceModel> whole_;
  Eigen::Index entries_ = 0;           // stored entries of whole_'s pattern (the size check)
  std::vector<int> meshElement_;       // this rank's elements (sub-mesh element -> mesh element)
  std::vector<int> meshVertex_;        // sub-mesh vertex -> mesh vertex
  std::unique_ptr<ForceModel> model_;  // null on a rank without elements
  std::vector<Eigen::Index> entry_;
  Eigen::VectorXd subDisplacement_, subForces_;
  Eigen::SparseMatrix<double> subTangent_;
};

}  // namespace

std::shared_ptr<ForceModel> makeRankSummedForceModel(const TetMesh& mesh, const ProblemSettings& physics,
                                                     std::shared_ptr<ForceModel> wholeMesh) {
  if (!wholeMesh) throw ValidationError("makeRankSummedForceModel: no whole-mesh force model");
  if (physics.forceModel == ForceModelType::linear) {
    throw ValidationError("makeRankSummedForceModel: the linear model (K u) has no element loop to distribute");
  }
  if (wholeMesh->numDofs() != mesh.numDofs()) {
    throw ValidationError("makeRankSummedForceModel: the force model has " + std::to_string(wholeMesh->numDofs()) +
                          " DOFs, the mesh " + std::to_string(mesh.numDofs()));
  }
  int ranks = 1;
  MPI_Comm_size(PETSC_COMM_WORLD, &ranks);
  if (ranks == 1) return wholeMesh;  // its elements are all of them: nothing to sum
  return std::make_shared<RankSummedForceModel>(mesh, physics, std::move(wholeMesh));
}

}  // namespace asyncfem
