// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/dynamics/dynamicSystem.hpp>
#include <asyncfem/forceModel/forceModel.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <memory>
#include <string>
#include <vector>

namespace asyncfem {

/// Where the time of a run went, and machine-independent counts.
struct IntegratorStats {
  double forceSeconds = 0.0;          ///< f_int and tangent element loops
  double assemblySeconds = 0.0;       ///< building system matrices / blocks from K, M
  double factorizationSeconds = 0.0;  ///< numeric factorizations (symbolic included)
  double solveSeconds = 0.0;          ///< back-substitutions and dense block products
  long long steps = 0;                ///< calls to step()
  long long factorizations = 0;
  long long solvedRightHandSides = 0;
  double factorFlops = 0.0;          ///< sum over factorizations, as the solver library reports
  double solveFlops = 0.0;           ///< sum over back-substitutions (estimate from factor non-zeros)
  std::vector<std::string> skipped;  ///< work the configuration made unnecessary, for the run summary
};

/// One fast region of a multirate integrator, as run summaries and messages show it.
struct RegionSummary {
  std::string name;
  int vertices = 0;       ///< vertices of the region
  int interfaceDofs = 0;  ///< free DOFs of L coupled to the region's elements
  int ratio = 1;          ///< substeps per large step, m
};

/// What an integrator says about a run beyond its state and statistics, for summaries,
/// resumes and drivers' checks: one value instead of one virtual per item.
struct RunReport {
  /// Non-zeros of the factors the integrator keeps, for cost reports (0: not reported).
  long long factorNonZeros = 0;
  /// Lines for run summaries (set-up against steady-state cost, iterations, ...), each
  /// without a trailing newline.
  std::vector<std::string> lines;
  /// Empty when a run resumed from a checkpoint (setState + setInternalState) continues
  /// bit for bit; else one line saying how it differs (a kept factor that no checkpoint
  /// holds), which drivers print when they resume.
  std::string resumeCaveat;
  /// True when this configuration may gain energy from step to step (the asynchronous
  /// integrator with the paper's coupling): drivers then estimate the step growth first.
  bool mayGainEnergy = false;
};

class MultirateIntegrator;

/// One time integrator: owns the state (u, v, t) of a DynamicSystem and advances it by
/// step(). The linear solves are done by a SparseSolver the integrator owns, so
/// integrators and solvers can be swapped independently.
///
/// State vectors are full (3n); fixed DOFs are kept at exactly zero.
class Integrator {
 public:
  Integrator(DynamicSystem system, double timestep);
  virtual ~Integrator() = default;
  Integrator(const Integrator&) = delete;
  Integrator& operator=(const Integrator&) = delete;

  /// Short name used in scenes and utilities ("backward-euler", "async", ...).
  virtual std::string name() const = 0;
  /// Advances the state by timestep() (for multirate integrators: one large step).
  virtual void step() = 0;
  /// Largest timestep this integrator is stable for on this system, or +inf when
  /// unconditionally stable (implicit methods).
  virtual double stableTimestepEstimate() const;

  /// Sets u and v (size 3n; fixed entries are zeroed) and the time. Step times after it
  /// are t_k = k h when time is such a k h (as a checkpoint's time is), else time + j h.
  void setState(const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity, double time = 0.0);
  /// What the next step() depends on beyond (u, v, t), for checkpoints: restoring
  /// (u, v, t) with setState() and then this with setInternalState() makes the following
  /// steps bit-identical to those of the integrator it was taken from. Factorizations
  /// and other quantities recomputed deterministically from (u, v, t) and h are not part
  /// of it; a factor kept from earlier steps is, as what rebuilds it. Empty when there is
  /// nothing (the default; backward Euler without a kept factor, symplectic Euler, the
  /// asynchronous integrator) or when the quantity is stale and would be recomputed from
  /// (u, v, t) anyway; the trapezoidal rule returns its acceleration a_k (3n), central
  /// differences its a_k on the free DOFs, backward Euler with a kept factor
  /// (IntegratorOptions::reuseFactor) the factor's state (BackwardEuler::internalState()).
  virtual Eigen::VectorXd internalState() const;
  /// Restores internalState(); call after setState(). An empty vector keeps the default
  /// (quantities derived from (u, v, t)). Throws asyncfem::Error if the size is not one
  /// internalState() returns for this integrator or the values are not finite.
  virtual void setInternalState(const Eigen::VectorXd& state);
  const Eigen::VectorXd& displacement() const { return displacement_; }
  const Eigen::VectorXd& velocity() const { return velocity_; }
  double time() const { return time_; }
  double timestep() const { return timestep_; }
  /// Marks a point a run may later be resumed from (drivers call it at the start of every
  /// frame, where checkpoints are taken): an integrator whose steps depend on history that
  /// neither (u, v, t) nor internalState() holds would let go of it here, so that a run
  /// resumed at this point continues bit for bit. Letting go costs speed at every frame
  /// (backward Euler once refactored here, at every frame: its kept factor is now in
  /// internalState() instead), so integrators should rather put such history into
  /// internalState(). Default: nothing.
  virtual void restartPoint() {}

  /// Changes h; implicit integrators refactor lazily at the next step.
  virtual void setTimestep(double timestep);

  /// What the integrator adds to run reports and drivers' decisions (RunReport); the
  /// default is an empty report.
  virtual RunReport report() const { return {}; }
  /// This integrator as a multirate one (fast regions, their vertices), or nullptr for a
  /// single-rate integrator. Lets drivers describe any integrator without knowing its type.
  virtual const MultirateIntegrator* multirate() const { return nullptr; }
  /// Whether the integrator uses DynamicSystem::externalForceJacobian (treats the external
  /// force's state-dependent part implicitly). IntegratorRegistry::create refuses a system
  /// that carries one for an integrator that does not.
  virtual bool linearizesExternalForce() const { return false; }

  const DynamicSystem& system() const { return system_; }
  /// Kinetic energy v^T M v / 2 plus the force model's elastic energy.
  double mechanicalEnergy() const;
  const IntegratorStats& stats() const { return stats_; }

 protected:
  /// The external force at time t and the current state (size 3n; zero if none).
  void evaluateExternalForce(double time, Eigen::VectorXd& forces) const;
  /// The time the current step ends at: t_{k+1} = t_origin + (k + 1) h, computed from the
  /// step index k so that step times do not accumulate round-off (t_origin = 0 from the
  /// start of a run; setState() and setTimestep() start a new origin unless the time is
  /// already a whole number of steps).
  double stepEndTime() const;
  /// Ends a step: time() becomes stepEndTime().
  void advanceTime();
  /// Ends every step the same way: throws asyncfem::NumericalError (naming the integrator,
  /// the time the step was heading to, and the first non-finite DOF as vertex and
  /// coordinate, with those in its location) if the new displacement or velocity (full,
  /// 3n) has a non-finite entry, leaving the state at the step's start; otherwise swaps
  /// them into the state (the arguments get the old state, as scratch for the next step),
  /// advances the time to stepEndTime() and counts the step.
  void commitStep(Eigen::VectorXd& displacement, Eigen::VectorXd& velocity);
  /// Zeroes the fixed entries of a full vector.
  void zeroFixed(Eigen::VectorXd& full) const;
  /// Called by setState() after the state changed, so that integrators that carry
  /// derived quantities (the acceleration of trapezoidal and central differences)
  /// recompute them before the next step. Default: nothing.
  virtual void stateChanged() {}

  DynamicSystem system_;
  Eigen::VectorXd displacement_;
  Eigen::VectorXd velocity_;
  double time_ = 0.0;
  double timestep_ = 0.0;
  IntegratorStats stats_;

 private:
  /// Step times are timeOrigin_ + stepIndex_ h (stepEndTime()).
  void restartTimeGrid();
  double timeOrigin_ = 0.0;
  long long stepIndex_ = 0;
};

}  // namespace asyncfem
