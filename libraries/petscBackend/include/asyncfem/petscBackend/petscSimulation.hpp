// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/hyperelasticFEM/hyperelasticOptions.hpp>
#include <asyncfem/petscBackend/solverSettings.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace asyncfem {

/// Time integrators of the PETSc backend; the equations are those of the single-process
/// BackwardEuler and Trapezoidal classes of the integrator library (see
/// docs/petsc-backend.md): one linearized (Newton) iteration per step for the nonlinear
/// models, the single-process default, or (backward Euler) Newton iterations with the
/// line search on the incremental potential (PetscNewtonSettings).
enum class PetscIntegratorKind { backwardEuler, trapezoidal };
/// Internal forces: linear FEM (K constant, the system matrix is assembled and its
/// preconditioner or factor built once), or a nonlinear model of the single-process
/// libraries evaluated on each rank's elements (tangent re-assembled every iteration):
/// corotated linear FEM (CorotationalLinearFEM, tangent PetscSimulationSettings::tangent)
/// and the hyperelastic materials (makeHyperelasticForceModel, options
/// PetscSimulationSettings::hyperelastic).
enum class PetscForceModelKind { linear, corotational, stvk, neoHookean, mooneyRivlin };

/// "backward-euler" / "trapezoidal" and "linear" / "corotational" / "stvk" /
/// "neo-hookean" / "mooney-rivlin"; parse functions throw ValidationError listing the
/// accepted names.
std::string toString(PetscIntegratorKind kind);
std::string toString(PetscForceModelKind kind);
PetscIntegratorKind parsePetscIntegratorKind(const std::string& name);
PetscForceModelKind parsePetscForceModelKind(const std::string& name);

/// Newton iterations of the backward Euler step for nonlinear models, with the meaning
/// of IntegratorOptions' fields of the same names (the single-process BackwardEuler):
/// maxIterations 1 is the linearized step; more iterate on the step equations until
/// |R|_2 <= tolerance |b_0|_2, each update (the linearized one included) shortened by
/// backtracking on the incremental potential when lineSearch is set.
struct PetscNewtonSettings {
  int maxIterations = 1;
  double tolerance = 1e-8;
  bool lineSearch = true;
};

/// Everything a distributed run needs besides the mesh. Every rank passes the same
/// values (the mesh and these settings are replicated; the matrices, vectors and solves
/// are distributed).
struct PetscSimulationSettings {
  PetscIntegratorKind integrator = PetscIntegratorKind::backwardEuler;
  PetscForceModelKind forceModel = PetscForceModelKind::linear;
  TangentKind tangent = TangentKind::simple;  ///< corotational model only
  HyperelasticOptions hyperelastic;           ///< stvk, neo-Hookean and Mooney-Rivlin only
  PetscNewtonSettings newton;                 ///< nonlinear models; > 1 iteration: backward Euler only
  MassType massType = MassType::consistent;
  double timestep = 0.01;          ///< h (time units), > 0
  double rayleighMass = 0.0;       ///< alpha (1/s), D = alpha M + beta K
  double rayleighStiffness = 0.0;  ///< beta (s)
  /// Vertices whose three DOFs are held at zero; removed from the systems (any order,
  /// duplicates allowed; ValidationError naming a vertex out of range).
  std::vector<int> fixedVertices;
  /// Gravity acceleration g (length / time^2): adds the body force M g (g on every
  /// vertex), computed element by element like the single-process M * stacked g.
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();
  /// A constant external force (3n, force units), or empty for none.
  Eigen::VectorXd constantForce;
  /// A time-dependent external force: adds f(t) to forces (3n, zeroed by the caller).
  /// Evaluated on every rank at every step end time (each rank keeps the entries of
  /// the DOFs it owns), so it must give the same values on every rank. It sees the
  /// time only, not the state. May be empty.
  std::function<void(double time, Eigen::VectorXd& forces)> timeDependentForce;
  PetscSolverSettings solver;
};

/// Counts and times of a run. Times are this rank's wall-clock seconds; counts global.
struct PetscRunStats {
  int ranks = 1;
  std::vector<int> elementsPerRank;  ///< the METIS partition's sizes
  std::vector<int> freeDofsPerRank;  ///< rows of the distributed systems each rank owns
  long long freeDofs = 0;            ///< rows of the distributed systems
  long long matrixNonZeros = 0;      ///< stored entries of the distributed system matrix
  std::string kspType;               ///< as PETSc resolved it after the options database
  std::string pcType;
  double setupSeconds = 0.0;     ///< partition, numbering, preallocation, first assembly
  double assemblySeconds = 0.0;  ///< element loops and matrix / vector assembly in steps
  double solveSeconds = 0.0;     ///< KSP solves including preconditioner / factor set-up
  long long steps = 0;
  long long solves = 0;
  long long solverIterations = 0;  ///< summed over solves (1 per direct solve)
  int lastIterations = 0;          ///< of the last step's solve
  long long newtonIterations = 0;  ///< linear systems solved for steps (1 per linearized step)
  int lineSearchHalvings = 0;      ///< of the last step
};

/// A body advanced in time on PETSc over MPI (every member is collective: all ranks
/// call it in the same order).
///
/// Distribution: the elements are partitioned by METIS (partitionElements(), computed
/// on rank 0 and broadcast); a vertex belongs to the lowest rank among those of its
/// elements; the free DOFs are numbered rank by rank (owned vertices in ascending id
/// order, three DOFs each), so each rank owns a contiguous block of rows. Each rank
/// assembles only its own elements into MATAIJ matrices (MATMPIAIJ on more than one
/// rank) with block size 3 and an exact preallocation computed from the mesh
/// connectivity; entries of rows another rank owns travel through PETSc's assembly
/// (MatSetValues with ADD_VALUES, MatAssemblyBegin/End). After the first assembly
/// MAT_NEW_NONZERO_ALLOCATION_ERR is set and re-assembly (corotational tangent, new
/// system coefficients) only rewrites values of the fixed pattern. Fixed DOFs are
/// removed from the numbering (negative indices that MatSetValues skips), as the
/// single-process integrators do, so the systems stay SPD for CG and Cholesky and have
/// no identity rows to distort AMG. The displacement is a ghosted Vec: each rank reads
/// the DOFs of its elements' vertices owned elsewhere through VecGhostUpdate.
///
/// Errors: PETSc failures become asyncfem::Error; bad settings ValidationError; a rank
/// whose element computations, checks or force callback throw makes every rank throw
/// the same exception ("rank R: ..."), so no rank waits forever; a diverged solve or a
/// non-finite state throws NumericalError on every rank naming the step (and the vertex).
class PetscSimulation {
 public:
  /// Builds the partition, numbering, matrices (M, K at rest) and solvers. The state
  /// starts at rest (u = v = 0, t = 0). Needs a live PetscRuntime.
  PetscSimulation(const TetMesh& mesh, const PetscSimulationSettings& settings);
  ~PetscSimulation();
  PetscSimulation(const PetscSimulation&) = delete;
  PetscSimulation& operator=(const PetscSimulation&) = delete;

  /// Advances u, v (and the trapezoidal acceleration) by one timestep.
  void step();
  /// Sets u and v (full 3n vectors, the same on every rank; fixed entries are ignored)
  /// and the time. Throws ValidationError on a size mismatch or non-finite values.
  void setState(const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity, double time = 0.0);
  /// What the next step needs beyond u, v and t, as the single-process integrators'
  /// internalState(): the trapezoidal rule's acceleration a_k (3n, on rank 0; empty
  /// elsewhere, and empty on every rank before the first step or after setState(), when
  /// a_k is still to be computed); empty for backward Euler. Collective.
  Eigen::VectorXd gatherInternalState() const;
  /// Restores it after setState() (checkpoints): the same full vector on every rank, or
  /// empty (a_k is then computed from the equation of motion, as after setState()).
  /// ValidationError on a size mismatch, non-finite values or a non-empty state for
  /// backward Euler. Collective.
  void setInternalState(const Eigen::VectorXd& state);
  /// The full displacement / velocity (3n, fixed DOFs 0) on rank 0; empty elsewhere.
  Eigen::VectorXd gatherDisplacement() const;
  Eigen::VectorXd gatherVelocity() const;

  double time() const;
  double timestep() const;
  int rank() const;
  int numRanks() const;
  /// Element ids this rank assembles (ascending).
  const std::vector<int>& localElements() const;
  const PetscRunStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The result of runPetscSimulation(): on rank 0 the displacement after each step
/// (numSteps full 3n vectors, fixed DOFs 0), empty on the other ranks; the stats of
/// the calling rank.
struct PetscTrajectory {
  std::vector<Eigen::VectorXd> displacements;
  PetscRunStats stats;
};

/// Runs numSteps steps from rest and gathers every step's displacement on rank 0.
/// Collective; needs a live PetscRuntime. For long runs prefer PetscSimulation with
/// gatherDisplacement() per output frame (memory).
PetscTrajectory runPetscSimulation(const TetMesh& mesh, const PetscSimulationSettings& settings, int numSteps);

}  // namespace asyncfem
