// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <mpi.h>
#include <petscmat.h>
#include <petscvec.h>

#include <Eigen/Core>
#include <asyncfem/hexElements/hexElementMatrices.hpp>
#include <asyncfem/petscBackend/petscSimulation.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <functional>
#include <memory>
#include <vector>

#include "detail/distributedLayout.hpp"
#include "detail/localForceModel.hpp"
#include "detail/petscHandle.hpp"

namespace asyncfem::detail {

/// What a local element's mass and linear stiffness need (rest shape, material); a
/// hexahedron's rest shape is in DistributedSystem::hexRest and only volume and density
/// are set here.
struct ElementData {
  ElementPositions rest;
  Eigen::Matrix<double, 3, 4> gradients;  ///< shape-function gradients, rest configuration
  double volume = 0.0;                    ///< signed
  double density = 0.0;
};

/// The distributed body of a simulation, everything but the time stepping and the
/// linear solvers: the layout (who owns which elements and DOFs, DistributedLayout), the
/// local elements' rest data, the matrices M and K (K(u) for nonlinear models, from the
/// rank's LocalForceModel) and
/// the system matrix that combines them on their shared pattern, the state and work
/// vectors (displacement ghosted), the static external force M g + constant force, and
/// the scatter of full vectors to rank 0. Collective: every rank constructs it from the
/// same mesh and settings.
struct DistributedSystem {
  /// Partitions the mesh (METIS on rank 0, broadcast), numbers the DOFs, assembles M and
  /// K at rest, creates the vectors (u = v = 0) and the static force, and attaches the
  /// rigid-body near null space (for GAMG) to M and the system matrix.
  DistributedSystem(MPI_Comm comm, const TetMesh& mesh, const PetscSimulationSettings& settings);

  PetscInt ownedDofs() const { return 3 * layout.ownedBlocks; }
  PetscInt globalDofs() const { return 3 * layout.numBlocks; }

  /// system = massWeight M + stiffnessWeight K (values only; the pattern is M's), plus
  /// extraWeight extra when extra is not null (a matrix of the same pattern).
  void combineSystem(double massWeight, double stiffnessWeight, Mat extra = nullptr, double extraWeight = 0.0);
  /// Nonlinear models: f_int(u) into internalForce and, unless tangent is null, K(u) into
  /// tangent (stiffness or iterateStiffness), u the ghosted vector given (displacement or
  /// trial); ghosts refreshed first.
  void assembleNonlinear(Vec ghostedDisplacement, Mat tangent);
  /// Nonlinear models: the elastic energy of the whole body at u (ghosted; summed over ranks).
  double elasticEnergy(Vec ghostedDisplacement);
  /// externalForce = static force + timeDependentForce(t) (if any), checked on every rank.
  void evaluateExternalForce(double t, const std::function<void(double, Eigen::VectorXd&)>& timeDependentForce);
  /// The full (3n, fixed DOFs 0) form of a distributed vector on rank 0; empty elsewhere.
  Eigen::VectorXd gather(Vec vector) const;
  /// Copies the owned entries of a full (3n, original numbering) vector into vector.
  void scatterOwned(const Eigen::VectorXd& full, Vec vector) const;
  /// Local element k's mass (lumped or consistent) and linear stiffness, 12 x 12 for a
  /// tetrahedron and 24 x 24 for a hexahedron.
  Eigen::MatrixXd elementMass(std::size_t k, MassType massType) const;
  Eigen::MatrixXd elementStiffness(const TetMesh& mesh, std::size_t k) const;
  /// The lowest vertex with a non-finite u or v over all ranks, or -1.
  int lowestNonFiniteVertex() const;

  MPI_Comm comm;
  int numDofs = 0;  ///< 3n
  bool nonlinear = false;
  DistributedLayout layout;
  std::vector<ElementData> elements;            ///< per local element
  std::vector<HexElementPositions> hexRest;     ///< per local element of a hexahedral mesh (empty otherwise)
  std::unique_ptr<LocalForceModel> forceModel;  ///< nonlinear models only

  /// iterateStiffness: K at a Newton iterate (nonlinear models with Newton iterations).
  MatHandle mass, stiffness, iterateStiffness, system;
  NullSpaceHandle nearNullSpace;
  VecHandle displacement;  ///< ghosted
  VecHandle trial;         ///< ghosted: a Newton iterate's u (nonlinear models)
  VecHandle velocity, acceleration, staticForce, externalForce, internalForce, rhs, increment, work, product;
  VecHandle residual, correction, candidate;  ///< Newton iterations and line search
  ScatterHandle toRoot;
  VecHandle rootVector;

 private:
  void partition(const TetMesh& mesh, const std::vector<int>& fixedVertices);
  void createVector(VecHandle& vector) const;
  void createMatrix(MatHandle& matrix) const;
  template <class ElementFunction>
  void assembleMatrix(Mat matrix, const ElementFunction& elementMatrix);
  void assembleMassAndStiffness(const TetMesh& mesh, const PetscSimulationSettings& settings);
  void createVectors();
  void assembleStaticForce(const PetscSimulationSettings& settings);
  void attachNearNullSpace(const TetMesh& mesh);
};

}  // namespace asyncfem::detail
