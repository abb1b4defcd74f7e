// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/asyncIntegrator/asyncOptions.hpp>
#include <asyncfem/asyncIntegrator/partitionedIntegrator.hpp>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/asyncIntegrator/runTimeRegions.hpp>
#include <asyncfem/asyncIntegrator/stepSolver.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <exception>
#include <functional>
#include <memory>
#include <vector>

namespace asyncfem {
namespace detail {
class WholeSystemFactor;
class StepSolver;
class HierarchyStepSolver;
struct StepContext;
struct CachedSetUp;
}  // namespace detail

/// Asynchronous implicit backward Euler (Zhao, Li & Barbič 2016, with the equations of
/// docs/asynchronous-integrator.md), for any partition: fast regions that touch or nest
/// too. Each set-up chooses its step solver (chooseStepSolver(), AsyncStepSolver): the
/// two-level structured Schur solve or its naive LU reference for regions that each
/// couple only to L, the hierarchy solve (Eqs. N1-N12) for regions that touch or nest or on
/// request. Fast regions S_i take m_i backward Euler substeps of
/// hS_i = hL / m_i per large step hL = timestep() while L takes one, coupled implicitly
/// (AsyncCoupling: by default L moves at its end-of-step velocity and receives the
/// interface elements' force averaged over the substeps, which never gains energy).
///
/// The stable coupling needs the tangent of each interface element: from the force
/// model's elementTangent(), or, for linear models built from a matrix, from the mesh's
/// linear element stiffness (the model's K is then checked against the mesh's on the
/// interface columns; a mismatch throws asyncfem::ValidationError).
///
/// Set-up is explicit: the constructor calls setUp() with the regions given, and setUp()
/// may be called again between steps with another partition of the same mesh (the state
/// is synchronous at large-step boundaries, so nothing has to be transferred). It cuts
/// every block on its pattern and finds the interface elements; for linear force models
/// it also builds and factors every block, Z and H^{LL*} (again only after setTimestep).
/// Nonlinear force models (corotational, hyperelastic): f_int(u_0) and K(u_0) are evaluated
/// once per large step and every block is refactored numerically (the paper's Algorithm 2,
/// or with the H^{LL*} factor kept: AsyncOptions::KeptFactors::laggedSchur); symbolic analyses are done
/// once per partition.
class AsyncBackwardEuler final : public PartitionedIntegrator {
 public:
  /// system.mesh must be set (Problem::dynamicSystem() sets it): the regions are vertex
  /// sets of it. largeTimestep hL in seconds. Throws asyncfem::ValidationError for a
  /// partition RegionPartition rejects or a system without a mesh.
  AsyncBackwardEuler(DynamicSystem system, double largeTimestep, std::vector<AsyncRegion> regions,
                     AsyncOptions options = {});
  /// The same for a system assembled by hand without its mesh: mesh is copied into it.
  AsyncBackwardEuler(const TetMesh& mesh, DynamicSystem system, double largeTimestep, std::vector<AsyncRegion> regions,
                     AsyncOptions options = {});
  /// The same with a partition built already on system.mesh and system.freeDofs (a scene
  /// reader that validated it builds it once).
  AsyncBackwardEuler(DynamicSystem system, double largeTimestep, RegionPartition partition, AsyncOptions options = {});
  ~AsyncBackwardEuler() override;

  /// Takes a new partition of system().mesh's vertices (built on system().freeDofs) from
  /// the next step on: every block, factor and analysis of the old one is dropped, and the
  /// step solver is chosen anew (chooseStepSolver(); AsyncOptionError for what it refuses).
  void setUp(RegionPartition partition);
  /// The step solver of the partition in use.
  AsyncStepSolver stepSolver() const;

  /// Hierarchy solve only (else asyncfem::Error): unknowns of the step system (2 sum over
  /// free DOFs of their step counts), whether it is solved level by level (else by one LU;
  /// known after the first step), and the last step's velocities v_{d,j} and displacement
  /// changes u_{d,j} - u_{d,0} of free DOF d (index into system().freeDofs.freeToFull()) at
  /// the end of its steps j = 1..N_d, in order (empty before the first step).
  long long stepSystemUnknowns() const;
  bool hierarchyByLevel() const;
  Eigen::VectorXd stepVelocities(int freeDof) const;
  Eigen::VectorXd stepDisplacements(int freeDof) const;

  /// Regions chosen at run time from the next step on (docs/asynchronous-integrator.md,
  /// "Run-time regions"): at every large-step boundary the policy may replace the
  /// partition (setUp with the new one, or a cached set-up of an earlier identical one).
  /// Throws asyncfem::ValidationError for options RunTimeRegionPolicy rejects, and for the
  /// contact policy on a system without obstacles (DynamicSystem::obstacleProximity).
  void setRunTimeRegions(RunTimeRegionOptions options);
  /// A line the run summary (report().lines) starts with, e.g. what an proposed region
  /// proposal decided (regionProposalSummary); empty: none.
  void setRegionNote(std::string note) { regionNote_ = std::move(note); }
  /// Every change of partition so far, in order.
  const std::vector<RepartitionRecord>& repartitions() const { return repartitions_; }

  std::string name() const override { return "async"; }
  void step() override;
  void setTimestep(double timestep) override;
  /// With the stable coupling and the structured method on one process: implicit contact
  /// (docs/asynchronous-integrator.md, "Implicit contact").
  bool linearizesExternalForce() const override;

  const AsyncOptions& options() const { return options_; }
  void setSubstepObserver(SubstepObserver observer) { observer_ = std::move(observer); }

  /// max_i ||C_i - C_i^T||_F / ||C_i||_F of the Schur corrections C_i (0 with no
  /// interface): how far H^{LL*} is from symmetric, what the symmetric mode neglects.
  double schurAsymmetry() const { return schurReport_.asymmetry; }
  /// Seconds spent computing the Z columns and the Schur corrections C_i (included in
  /// stats().factorizationSeconds): the part of a refactorization the paper's Algorithm 2
  /// adds over single-rate.
  double zColumnSeconds() const { return schurReport_.zColumnSeconds; }
  /// The Schur mode in effect (lowRank is symmetric for the stable coupling, and may fall
  /// back to lu for very large interfaces).
  SchurMode schurModeUsed() const { return schurReport_.modeUsed; }
  /// Set-up, rebuild and steady-state step times, and the sizes that set them.
  const AsyncRunStats& runStats() const { return runStats_; }
  /// factorNonZeros(), the set-up, rebuild and steady-step times and the lagged-Schur
  /// counts of runStats(), and whether the coupling may gain energy (the paper's).
  RunReport report() const override;

  /// Seconds per large step of the sparse triangular solves alone, with the current
  /// factors and random right-hand sides (median of `repeats`): per region 2 m_i solves
  /// with A^{S_i} (m_i with denseZ recovery), plus one with H^{LL*}; for the naive method,
  /// one solve with the full system. The floor under the structured step's cost, for
  /// benchmarks. Needs one step() first (throws asyncfem::Error otherwise).
  double solveFloorSeconds(int repeats = 5);
  /// Sum over the factorizations this integrator owns of the solver libraries' factor
  /// non-zeros (machine-independent size of the factors).
  long long factorNonZeros() const;

 private:
  // The step solvers and a set-up kept for reuse (src/stepSolvers.hpp).
  using CachedSetUp = detail::CachedSetUp;
  void initialize();
  void checkPartitionFits(const RegionPartition& partition) const;
  detail::StepContext stepContext();
  const detail::HierarchyStepSolver& hierarchySolver(const char* what) const;
  // Run-time regions (setUpCache.cpp).
  void maybeRepartition();
  void repartition(std::vector<AsyncRegion> regions, const std::string& reason);
  AsyncOptions options_;
  SubstepObserver observer_;
  detail::SchurReport schurReport_;
  AsyncRunStats runStats_;
  // The step solver of the partition in use.
  std::unique_ptr<detail::StepSolver> solver_;
  // The whole single-rate system's factor (quickSetUp), shared by every partition.
  std::unique_ptr<detail::WholeSystemFactor> whole_;
  std::unique_ptr<RunTimeRegionPolicy> policy_;
  std::vector<RepartitionRecord> repartitions_;
  long long stepsKept_ = 0;  // large steps since the last change of partition
  std::vector<CachedSetUp> cache_;
  std::string regionNote_;
};

}  // namespace asyncfem
