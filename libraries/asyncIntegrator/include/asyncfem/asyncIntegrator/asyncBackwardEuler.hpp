// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>

#include <Eigen/Core>

#include <functional>
#include <memory>
#include <vector>

namespace asyncfem {

/// How H^{LL*} = A^L - sum_i H^{L S_i} (H^{S_i S_i})^{-1} H^{S_i L} is factored.
enum class SchurMode {
  exact,      ///< unsymmetric LU (UMFPACK): the exact asynchronous step
  symmetric,  ///< Cholesky of its symmetric part: faster, approximate
};
/// How one large step's block system is solved.
enum class AsyncSolveMethod {
  structured,  ///< forward substitution + Schur complement on L: O(m) per step
  naive,       ///< the whole (sum_i 3 m_i |S_i| + 3|L|) system, LU: the reference
};
/// How the S unknowns are recovered once Y is known (structured method only).
enum class RecoveryMode {
  substitution,  ///< a second forward substitution (m_i sparse solves per region)
  denseZ,        ///< X = y - Z Y_I with Z = (H^{SS})^{-1} H^{SI} stored densely (m_i |S_i| x |I_i|)
};

struct AsyncOptions {
  SchurMode schur = SchurMode::exact;
  AsyncSolveMethod method = AsyncSolveMethod::structured;
  RecoveryMode recovery = RecoveryMode::substitution;
  SolverKind regionSolver = SolverKind::cholmod;  ///< factors A^{S_i} (SPD)
};

/// Called after a large step for every substep r = 1..m_i of fast region i, only when a
/// caller installed it: time of the substep and the region's displacement and velocity at
/// it, ordered as partition().regionDofs(i).
using SubstepObserver = std::function<void(int region, int substep, double time,
                                           const Eigen::VectorXd& regionDisplacement,
                                           const Eigen::VectorXd& regionVelocity)>;

/// Asynchronous implicit backward Euler (Zhao, Li & Barbič 2016; equations as corrected in
/// the design note shared/design/async-backward-euler.md). Fast regions S_i take m_i
/// backward Euler substeps of hS_i = hL / m_i per large step hL = timestep() while L takes
/// one, coupled implicitly: L's velocity is interpolated linearly inside the large step.
///
/// Linear force models: every block, Z and H^{LL*} are built and factored once (and again
/// only after setTimestep). Nonlinear force models (corotational): f_int(u_0) and K(u_0) are
/// evaluated once per large step and every block is refactored numerically (the paper's
/// Algorithm 2); symbolic analyses are done once per run.
class AsyncBackwardEuler final : public Integrator {
public:
  AsyncBackwardEuler(const TetMesh& mesh, DynamicSystem system, double largeTimestep, std::vector<AsyncRegion> regions,
                     AsyncOptions options = {});
  ~AsyncBackwardEuler() override;

  std::string name() const override { return "async"; }
  void step() override;
  void setTimestep(double timestep) override;

  const RegionPartition& partition() const { return partition_; }
  const AsyncOptions& options() const { return options_; }
  void setSubstepObserver(SubstepObserver observer) { observer_ = std::move(observer); }

  /// max_i ||C_i - C_i^T||_F / ||C_i||_F of the Schur corrections C_i (0 with no
  /// interface): how far H^{LL*} is from symmetric, what the symmetric mode neglects.
  double schurAsymmetry() const { return schurAsymmetry_; }

private:
  struct Impl;
  void rebuildBlocks();
  RegionPartition partition_;
  AsyncOptions options_;
  SubstepObserver observer_;
  double schurAsymmetry_ = 0.0;
  std::unique_ptr<Impl> impl_;
};

}  // namespace asyncfem
