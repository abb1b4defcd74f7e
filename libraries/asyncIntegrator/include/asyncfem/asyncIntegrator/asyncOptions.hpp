// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

// The choices and the run statistics of the asynchronous integrator (AsyncBackwardEuler).
namespace asyncfem {

/// How H^{LL*} = A^L - sum_i H^{L S_i} (H^{S_i S_i})^{-1} H^{S_i L} is factored.
enum class SchurMode {
  /// Exact, and the default. For the stable coupling, whose H^{LL*} is symmetric, this is
  /// a Cholesky factor of H^{LL*} itself (what `symmetric` does; one sparse solve per step;
  /// lu if the corrections are measurably unsymmetric, above 1e-10). For the paper's
  /// coupling: H^{LL*} = A^L - U C U^T differs from the SPD A^L only by the dense interface
  /// block C, so A^L is factored by Cholesky and C enters through a q x q capacitance
  /// matrix (q = interface DOFs; W = (A^L)^{-1} U, |L| x q, is stored). Falls back to lu
  /// when W would exceed 512 MiB.
  lowRank,
  lu,  ///< exact: unsymmetric LU (UMFPACK) of H^{LL*} itself, as in the paper
  /// Cholesky of the symmetric part of H^{LL*}, as in the paper: approximate for the paper
  /// coupling; exact (to round-off) for the stable one, whose H^{LL*} is symmetric.
  symmetric,
};
/// How one large step's system is solved (docs/asynchronous-integrator.md, "The step
/// solvers"). AsyncBackwardEuler chooses the solver from this and the partition's shape
/// (asyncStepSolver()): regions that touch or nest always take the hierarchy solve.
enum class AsyncSolveMethod {
  structured,  ///< forward substitution + Schur complement on L: O(m) per step
  naive,       ///< the whole (sum_i 3 m_i |S_i| + 3|L|) system, LU: the reference
  /// The time-local step system of every DOF's steps (Eq. N5), solved level by level or by
  /// one sparse LU (AsyncOptions::nestedSolve): what regions that touch or nest always run;
  /// for other regions the same trajectory as structured, for comparison.
  hierarchy,
};
/// How the hierarchy solve (AsyncSolveMethod::hierarchy, and every partition whose regions
/// touch or nest) solves its step system (docs/asynchronous-integrator.md, "The solve").
enum class NestedSolve {
  /// structured when the step counts form a chain (each divides the next, e.g. 1, 8, 32),
  /// the LU otherwise
  automatic,
  /// level by level, one factor per level (Eqs. N9-N12); asyncfem::ValidationError when the
  /// counts do not form a chain
  structured,
  /// one sparse LU of the whole step system (Eq. N8), for any counts N6 allows
  lu,
};
/// "automatic", "structured", "lu".
std::string toString(NestedSolve solve);
/// Inverse of toString; throws asyncfem::ValidationError naming the valid values.
NestedSolve parseNestedSolve(const std::string& name);
/// How the S unknowns are recovered once Y is known (structured method only).
enum class RecoveryMode {
  automatic,     ///< per region, whichever of the two below needs fewer flops (Z up to 128 MiB)
  substitution,  ///< a second forward substitution (m_i sparse solves per region)
  /// The end-of-step state needs only X_m and sum_r X_r: X_m = y_m - Z_m Y_I and
  /// sum_r X_r = sum_r y_r - (sum_r Z_r) Y_I, with Z_m and sum_r Z_r stored densely
  /// (2 |S_i| x |I_i|), 4 |S_i| |I_i| flops per step whatever m_i. With a substep observer
  /// installed the substeps are recovered by substitution.
  denseZ,
};

/// How a set-up (or a nonlinear rebuild) computes each region's Z = (H^{SS})^{-1} H^{SI} and its
/// Schur correction C_i (docs/asynchronous-integrator.md, "Z from the region's modes").
enum class ZSolve {
  /// Per region, from the modes where their price in flops (about 9 |S_i|^3) is below a
  /// quarter of the substitutions' (m_i |I_i| solves), else by substitution; regions with
  /// contact blocks by substitution.
  automatic,
  substitution,  ///< m_i |I_i| forward substitutions with A^S (solves in column blocks)
  /// One dense generalized eigendecomposition of (K^{SS}, M^{SS}) per region; a region where
  /// it does not apply (contact blocks, a non-symmetric tangent) is substituted.
  modes,
};

/// How a fast region and L exchange forces inside a large step (docs/asynchronous-integrator.md,
/// section "Method", Eqs. A4-A12).
enum class AsyncCoupling {
  /// The default. L moves at its end-of-step velocity inside the large step, interface
  /// elements are subcycled with S and L receives their force averaged over the substeps.
  /// The discrete energy of a free linear run never increases, for every ratio m.
  stable,
  /// Zhao, Li & Barbic 2016 as published: L's velocity interpolated linearly, the interface
  /// force on L taken at the end of the step. Only conditionally stable in m.
  paper,
};

/// The options of AsyncBackwardEuler, grouped by concern: how the step is solved (the
/// members at the top), the factors kept across steps and set-ups (keptFactors), contact
/// (contact) and runs on several processes (processes). The scene keys of
/// docs/scene-format.md ("integrator.options") are read and written by one codec
/// (asyncSettingsJson, registration.hpp); chooseStepSolver() checks them against the
/// partition.
struct AsyncOptions {
  // How the step is solved.
  AsyncCoupling coupling = AsyncCoupling::stable;
  SchurMode schur = SchurMode::lowRank;
  AsyncSolveMethod method = AsyncSolveMethod::structured;
  RecoveryMode recovery = RecoveryMode::automatic;
  ZSolve zSolve = ZSolve::automatic;
  /// The hierarchy solve's strategy (only where that solve runs).
  NestedSolve nestedSolve = NestedSolve::automatic;
  SolverKind regionSolver = SolverKind::cholmod;  ///< factors A^{S_i} (SPD)
  /// Regions of at most this many free DOFs factor A^{S_i} dense (SolverKind::dense) and
  /// multiply by hS^2 K^{SS} dense, whatever regionSolver says: there the m substitutions
  /// per large step cost less dense than sparse (docs/asynchronous-integrator.md,
  /// "Performance notes"). 0: every region uses regionSolver.
  int denseRegionDofs = 128;
  /// Threads for the set-up and per-large-step rebuild (columns of Z in blocks, one A^S
  /// factor copy per block) and for the regions of a step: 0 = OpenMP's maximum.
  int threads = 0;
  /// Factors kept across large steps and partitions.
  struct KeptFactors {
    /// Nonlinear forces only. false: every large step recomputes Z and refactors H^{LL*}
    /// (the paper's Algorithm 2). true (default): the factor of H^{LL*} from the last full
    /// rebuild is kept as a preconditioner and the Schur system of the current tangent is
    /// solved by preconditioned iterative refinement (each iteration: one forward substitution
    /// per region and one solve with the old factor) to a relative residual of
    /// laggedSchurTolerance. Rent or buy, priced in flops: a step may take as many
    /// iterations as one rebuild costs (at least laggedSchurIterations); beyond that it does
    /// the full rebuild instead, and so does the next step after a slow convergence (more than
    /// half of them) or once the iterations since the last rebuild have cost a rebuild.
    /// A^S is refactored every step either way. The step then solves the coupled system to
    /// the tolerance instead of to round-off.
    bool laggedSchur = true;
    /// With laggedSchur: the kept factor preconditions turned with the body, T P T^T with
    /// T the block diagonal of every vertex's rotation since the factor was built (the polar
    /// rotation of its elements' mean deformation gradient from that state; docs/
    /// asynchronous-integrator.md, "The lagged factor turned with the body"). A corotational
    /// or hyperelastic tangent that has turned with the body since the rebuild satisfies
    /// K ~ T K_ref T^T, so fewer iterations and rebuilds are needed where parts of the body
    /// swing. The solution is the same to laggedSchurTolerance either way. Not with
    /// largeSystemSolver (an external solver's preconditioner is its own). Also, every other
    /// rebuild that the rent-or-buy rule asks for is a refresh: the kept corrections C_i
    /// turned with the body and H^{LL*} refactored from the current A^L, without Z (the
    /// m |I| solves); the next one is a full rebuild.
    bool laggedSchurRotation = true;
    int laggedSchurIterations = 8;
    double laggedSchurTolerance = 1e-10;
    /// Stable coupling, structured method only (docs/asynchronous-integrator.md, "Quick
    /// set-up"). false (default): a set-up computes Z and factors H^{LL*}, and every step
    /// solves exactly. true: a set-up factors only the regions' A^S; L's system is solved
    /// by conjugate gradients preconditioned with the factor of the whole single-rate system
    /// A = M + hL D + hL^2 K (one factor for every partition, refactored only for a new hL;
    /// exact when every ratio is 1) to a relative residual of laggedSchurTolerance. Once the
    /// iterations have cost as much as the rebuild they put off (its estimate: the whole
    /// factor's time plus one forward substitution per interface DOF), or when they need
    /// more than quickSetUpIterations, Z and H^{LL*} are built as without it.
    bool quickSetUp = false;
    int quickSetUpIterations = 60;
    /// false: a partition never leaves the quick path while its solves converge (studies of
    /// the deflation; the rent-or-buy rule is off).
    bool quickSetUpRebuild = true;
  };
  KeptFactors keptFactors{};
  /// State-dependent external forces (contact).
  struct Contact {
    /// State passed to the external force function at substep r of a fast region: false
    /// (default) passes the large step's start state (u_0, v_0), so state-dependent forces
    /// such as penalty contact act once per large step, as in the paper; true passes the
    /// predicted state (u_0 + r hS v_0, v_0), so contacts of S vertices are tested at every
    /// substep (an explicit prediction: the substep states themselves are unknowns of the
    /// implicit solve).
    bool substepStatePrediction = false;
    /// Implicit contact (DynamicSystem::externalForceJacobian; docs/asynchronous-integrator.md,
    /// "Implicit contact"): the step is solved again with the external force at the last
    /// solve's substep and end states until its largest change, relative to the step's
    /// right-hand side, is at most tolerance, at most iterations solves (then
    /// counted as unconverged, or an error above a relative change of 1).
    double tolerance = 1e-8;
    int iterations = 30;
    /// Implicit contact: a step whose first solve provably touches no obstacle at any
    /// substep (Eq. C6 of docs/asynchronous-integrator.md: bounds on every vertex's motion,
    /// DynamicSystem::stateDependentOnlyInContact) ends there, recovering each region's end
    /// state from the stored Z instead of every substep's. false: every step evaluates the
    /// force at every substep state (the same result to round-off, at about 1.6x the cost
    /// of a step far from contact).
    bool certifyContactFree = true;
  };
  Contact contact{};
  /// Runs on several processes (MPI): L's system solved outside, regions owned by one process.
  struct Processes {
    /// The solver of L's system H^{LL*} (structured method, stable coupling), or empty for
    /// CHOLMOD. Called at each set-up with the global DOF ids of L (ascending; the rows of
    /// H^{LL*}) and, for each fast region i, the global DOF ids of its interface I_i (the rows
    /// and columns its dense block C_i couples; a distributed solver keeps each on one rank
    /// where it can); the solver it returns is given the assembled H^{LL*} (every entry of each
    /// dense interface block on a fixed pattern, both triangles, symmetric) and must solve it
    /// to the accuracy the run needs; an iterative one that asks for a preconditioning matrix
    /// (SparseSolver::usesPreconditionerMatrix) gets Â^L, the same without the dense blocks. The petscBackend library's
    /// makePetscLargeSystemSolver() solves it distributed over MPI ranks (docs/petsc-backend.md, "The asynchronous
    /// integrator over MPI"). The paper's coupling (unsymmetric H^{LL*}) is refused with it.
    using LargeSystemSolverFactory = std::function<std::unique_ptr<SparseSolver>(
        const std::vector<int>& largeDofs, const std::vector<std::vector<int>>& interfaceDofs)>;
    LargeSystemSolverFactory largeSystemSolver{};
    /// A run on several processes that step the same integrator on the same state (MPI
    /// ranks): each fast region is computed by one process only, its owner (the factor of
    /// A^S, Z and C_i, the forward substitutions and the recovery of its substeps), and
    /// what the others need of it is summed over the processes: the corrections C_i (for
    /// H^{LL*}), each substitution's interface rows, the region's end-of-step velocities and
    /// the priced cost of its solves. Stable coupling and structured method only; a substep
    /// observer sees only this process's regions. Both members empty (the default): this
    /// process computes every region.
    struct RegionDistribution {
      /// At each set-up, with every region's free DOFs and interface DOFs (global ids): 1
      /// for each region this process computes. Every region needs exactly one owner (checked
      /// with sum; otherwise a ValidationError naming the region, on every process).
      std::function<std::vector<char>(const std::vector<std::vector<int>>& regionDofs,
                                      const std::vector<std::vector<int>>& interfaceDofs)>
          ownedRegions;
      /// values[0, count) replaced by their sum over the processes. Collective: every process
      /// calls it at the same point with the same count, and all receive the same sums.
      std::function<void(double* values, std::size_t count)> sum;
    };
    RegionDistribution regionDistribution{};
  };
  Processes processes{};
};

/// Where an asynchronous run's time went, set-up apart from the steady-state steps (the
/// IntegratorStats of stats() hold the same time split by kind of work).
struct AsyncRunStats {
  /// First build (blocks, A^{S_i} factors, Z, the Schur corrections C_i, the H^{LL*}
  /// factor): the cost before the first step can be taken. Linear forces: paid once per
  /// timestep; nonlinear: the first step's rebuild.
  double setupSeconds = 0.0;
  double setupZSeconds = 0.0;      ///< of setupSeconds: Z columns and C_i
  double setupSchurSeconds = 0.0;  ///< of setupSeconds: assembling and factoring H^{LL*} (or A^L)
  /// Per-large-step rebuilds after the first (nonlinear forces: refactor A^S, Z, H^{LL*}).
  double rebuildSeconds = 0.0;
  double rebuildZSeconds = 0.0;  ///< of rebuildSeconds: Z columns and C_i
  long long rebuilds = 0;
  /// Everything else step() spends (forces, right-hand sides, solves, state update).
  double stepSeconds = 0.0;
  long long steps = 0;
  int fastDofs = 0;                               ///< sum_i |S_i|
  int interfaceDofs = 0;                          ///< sum_i |I_i|
  int largeDofs = 0;                              ///< |L|
  int zThreads = 1;                               ///< threads (A^S factor copies) the last Z computation used
  long long zColumns = 0;                         ///< right-hand sides of one Z computation: sum_i m_i |I_i|
  int zModalRegions = 0;                          ///< regions of the last Z computation taken from their modes
  long long laggedSteps = 0;                      ///< steps solved with the lagged H^{LL*} (AsyncOptions::laggedSchur)
  long long schurIterations = 0;                  ///< iterative refinement iterations over those steps
  long long laggedRefreshes = 0;                  ///< rebuilds that turned the kept C_i instead of computing Z
  double largestSchurResidual = 0.0;              ///< largest final relative residual of those steps
  long long quickSteps = 0;                       ///< steps solved on the whole system's factor (quickSetUp)
  long long quickIterations = 0;                  ///< conjugate gradient iterations over those steps
  double largestQuickResidual = 0.0;              ///< largest final relative residual of those steps
  long long quickEnds = 0;                        ///< partitions that left quick set-up for Z and H^{LL*}
  long long contactSteps = 0;                     ///< steps solved with implicit contact
  long long contactIterations = 0;                ///< solves over those steps
  long long unconvergedContactSteps = 0;          ///< of those, stopped at AsyncOptions::contactIterations
  double largestContactResidual = 0.0;            ///< largest relative residual of those
  long long contactRegionFactorizations = 0;      ///< A^S refactored for its contact blocks
  long long contactStepSystemFactorizations = 0;  ///< hierarchy solve: the step system's LU with contact blocks
  long long contactFreeSteps = 0;                 ///< of contactSteps, certified free of contact (Eq. C6)
  long long contactScreenedSteps = 0;             ///< of contactSteps, predicted states clear of obstacles (Eq. C7)
  long long contactPairBlocksDropped = 0;         ///< of contactSteps, went on without the regions' surface-pair blocks
  /// Mean seconds of a steady-state large step (stepSeconds / steps), and with rebuilds.
  double meanStepSeconds() const { return steps > 0 ? stepSeconds / static_cast<double>(steps) : 0.0; }
  double meanStepWithRebuildSeconds() const {
    return steps > 0 ? (stepSeconds + rebuildSeconds) / static_cast<double>(steps) : 0.0;
  }
};

/// Called after a large step for every substep r = 1..m_i of fast region i, only when a
/// caller installed it: time of the substep and the region's displacement and velocity at
/// it, ordered as partition().regionDofs(i).
using SubstepObserver =
    std::function<void(int region, int substep, double time, const Eigen::VectorXd& regionDisplacement,
                       const Eigen::VectorXd& regionVelocity)>;

}  // namespace asyncfem
