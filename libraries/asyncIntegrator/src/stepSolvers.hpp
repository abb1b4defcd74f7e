// SPDX-License-Identifier: BSD-3-Clause
// The step solvers of AsyncBackwardEuler behind one interface (docs/asynchronous-
// integrator.md, "The step solvers"). The integrator owns the state, the partition and its
// changes, and commits each step; a step solver is built for one partition and owns that
// partition's blocks, factors and solve: TwoLevelStepSolver (the structured Schur solve and
// its naive LU reference, twoLevelStepSolver.hpp) and HierarchyStepSolver (regions that
// touch or nest, hierarchyStepSolver.hpp). chooseStepSolver() (stepSolver.hpp) decides the
// kind, AsyncBackwardEuler::setUp builds it (makeStepSolver in asyncBackwardEuler.cpp). Private to the library.
#pragma once

#include <Eigen/Core>
#include <asyncfem/asyncIntegrator/asyncOptions.hpp>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/asyncIntegrator/stepSolver.hpp>
#include <asyncfem/dynamics/dynamicSystem.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace asyncfem::detail {

class WholeSystemFactor;

/// What a step solver reads of its integrator and where it adds its counts: references to
/// AsyncBackwardEuler's members, valid for the integrator's life. partition is the
/// integrator's partition in use: a solver kept for reuse (run-time regions) is stepped
/// only once its partition is back in place.
struct StepContext {
  const Integrator& integrator;  ///< timestep()
  const DynamicSystem& system;
  const AsyncOptions& options;
  const RegionPartition& partition;
  const Eigen::VectorXd& displacement;  ///< u_0 of each step
  const Eigen::VectorXd& velocity;      ///< v_0 of each step
  IntegratorStats& stats;
  AsyncRunStats& runStats;
  const SubstepObserver& observer;
  SchurReport& schur;
  /// The whole single-rate system's factor (AsyncOptions::KeptFactors::quickSetUp), shared by every
  /// partition; made by the first solver that needs it.
  std::unique_ptr<WholeSystemFactor>& whole;
};

/// The end state of one large step, in the solver's buffers (the integrator swaps them in).
struct StepEnd {
  Eigen::VectorXd& displacement;
  Eigen::VectorXd& velocity;
};

/// One partition's step system: set up explicitly, stepped, reported.
class StepSolver {
 public:
  explicit StepSolver(const StepContext& context)
      : integrator_(context.integrator),
        system_(context.system),
        options_(context.options),
        partition_(context.partition),
        displacement_(context.displacement),
        velocity_(context.velocity),
        stats_(context.stats),
        runStats_(context.runStats),
        observer_(context.observer),
        schurReport_(context.schur),
        whole_(context.whole) {}
  virtual ~StepSolver() = default;
  StepSolver(const StepSolver&) = delete;
  StepSolver& operator=(const StepSolver&) = delete;

  virtual AsyncStepSolver kind() const = 0;
  /// Builds for the context's partition (its patterns, blocks and, for linear forces, every
  /// factor, so that the first step costs a steady one). A solver of the same kind may be
  /// set up again for another partition, reusing its storage.
  virtual void setUp() = 0;
  /// The timestep changed: every factor is rebuilt at the next step.
  virtual void invalidateFactors() = 0;
  /// One large step from the context's (u_0, v_0) at t0 to t1.
  virtual StepEnd step(double t0, double t1) = 0;
  /// Sum over the factors this solver owns of their non-zeros.
  virtual long long factorNonZeros() const = 0;
  /// The run summary's lines after the one naming the solver.
  virtual void reportLines(std::vector<std::string>& lines) const = 0;

 protected:
  double timestep() const { return integrator_.timestep(); }
  /// The system asks for implicit contact and the options allow it (asyncLinearizesContact).
  bool implicitContact() const;

  const Integrator& integrator_;
  const DynamicSystem& system_;
  const AsyncOptions& options_;
  const RegionPartition& partition_;
  const Eigen::VectorXd& displacement_;
  const Eigen::VectorXd& velocity_;
  IntegratorStats& stats_;
  AsyncRunStats& runStats_;
  const SubstepObserver& observer_;
  SchurReport& schurReport_;
  std::unique_ptr<WholeSystemFactor>& whole_;
};

/// Whether options let the step take a contact force's Jacobian (implicit contact): the
/// structured and the hierarchy solves with the stable coupling on one process; the naive
/// reference, the paper's coupling and external solvers of L do not.
bool asyncLinearizesContact(const AsyncOptions& options);

/// The run summary's line on the steady large step and the rebuilds.
std::string steadyStepLine(const AsyncRunStats& r);
/// The run summary's line on implicit contact: perStep follows "per step" in the
/// parenthesis, stopped names what the limit counts, refactored ends the line.
std::string contactLine(const AsyncRunStats& r, const char* perStep, const char* stopped, int limit,
                        const std::string& refactored);

/// A set-up kept for reuse by run-time regions (the most recently used first).
struct CachedSetUp {
  std::vector<std::pair<int, std::vector<int>>> key;  // (ratio, vertices) of every region, sorted
  RegionPartition partition;
  std::unique_ptr<StepSolver> solver;
  AsyncRunStats sizes;  // fastDofs, interfaceDofs, largeDofs
  double timestep = 0.0;
};

}  // namespace asyncfem::detail
