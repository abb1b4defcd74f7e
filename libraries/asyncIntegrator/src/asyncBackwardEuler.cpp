// SPDX-License-Identifier: BSD-3-Clause
// Asynchronous implicit backward Euler: construction, set-up (the step solver chosen by
// chooseStepSolver and made by makeStepSolver) and one large step. The integrator owns the
// state, the partition and its changes (setUpCache.cpp: run-time regions) and the run
// summary (asyncReport.cpp); each partition's blocks, factors and solve belong to its step
// solver (stepSolvers.hpp): twoLevelStepSolver.cpp and its parts, hierarchyStepSolver.cpp.
#include <Eigen/Core>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <string>

#include "detail/wholeSystemFactor.hpp"
#include "hierarchyStepSolver.hpp"
#include "stepSolvers.hpp"
#include "twoLevelStepSolver.hpp"

namespace asyncfem {

namespace {

// The solver of kind for the context's partition, not yet set up.
std::unique_ptr<detail::StepSolver> makeStepSolver(AsyncStepSolver kind, const detail::StepContext& context) {
  if (kind == AsyncStepSolver::hierarchy) return std::make_unique<detail::HierarchyStepSolver>(context);
  return std::make_unique<detail::TwoLevelStepSolver>(kind, context);
}

}  // namespace

AsyncBackwardEuler::AsyncBackwardEuler(const TetMesh& mesh, DynamicSystem system, double largeTimestep,
                                       std::vector<AsyncRegion> regions, AsyncOptions options)
    : AsyncBackwardEuler(withMesh("async", mesh, std::move(system)), largeTimestep, std::move(regions), options) {}

AsyncBackwardEuler::AsyncBackwardEuler(DynamicSystem system, double largeTimestep, std::vector<AsyncRegion> regions,
                                       AsyncOptions options)
    : PartitionedIntegrator("async", std::move(system), largeTimestep, std::move(regions), true),
      options_(std::move(options)) {
  initialize();
}

AsyncBackwardEuler::AsyncBackwardEuler(DynamicSystem system, double largeTimestep, RegionPartition partition,
                                       AsyncOptions options)
    : PartitionedIntegrator("async", std::move(system), largeTimestep, std::move(partition)),
      options_(std::move(options)) {
  initialize();
}

void AsyncBackwardEuler::initialize() {
  if (!system_.damped()) stats_.skipped.push_back("damping blocks (alpha = beta = 0)");
  if (system_.forceModel->isLinear())
    stats_.skipped.push_back("per-step refactorization (linear forces: blocks, Z and H^{LL*} factored once)");
  if (options_.method == AsyncSolveMethod::naive)
    stats_.skipped.push_back("Schur complement (naive full-system solve)");
  setUp(partition_);
}

AsyncBackwardEuler::~AsyncBackwardEuler() = default;

void AsyncBackwardEuler::checkPartitionFits(const RegionPartition& partition) const {
  std::size_t partitioned = partition.largeDofs().size();
  for (int i = 0; i < partition.numRegions(); ++i) partitioned += partition.regionDofs(i).size();
  if (partition.vertexRegion().size() != static_cast<std::size_t>(system_.mesh->numVertices()) ||
      partitioned != system_.freeDofs.freeToFull().size()) {
    throw ValidationError("async integrator: setUp: the partition covers " +
                          std::to_string(partition.vertexRegion().size()) + " vertices and " +
                          std::to_string(partitioned) + " free DOFs, but the system has " +
                          std::to_string(system_.mesh->numVertices()) + " vertices and " +
                          std::to_string(system_.freeDofs.freeToFull().size()) +
                          " free DOFs: build it on system().mesh and system().freeDofs");
  }
}

detail::StepContext AsyncBackwardEuler::stepContext() {
  return {*this,  system_,   options_,  partition_,   displacement_, velocity_,
          stats_, runStats_, observer_, schurReport_, whole_};
}

void AsyncBackwardEuler::setUp(RegionPartition partition) {
  Stopwatch watch;
  checkPartitionFits(partition);
  // Regions that touch at one ratio step as one region (the same step counts): the solve
  // sees them merged, so only a partition with different ratios across an element needs the
  // hierarchy solve.
  partition = mergeTouchingAtOneRatio(*system_.mesh, system_.freeDofs, std::move(partition));
  const AsyncStepSolver kind = chooseStepSolver(options_, partition, system_);
  partition_ = std::move(partition);
  // A solver of the same kind is set up again in the storage of the previous partition.
  if (!solver_ || solver_->kind() != kind) solver_ = makeStepSolver(kind, stepContext());
  solver_->setUp();
  runStats_.setupSeconds += watch.stop();
}

bool AsyncBackwardEuler::linearizesExternalForce() const { return detail::asyncLinearizesContact(options_); }

void AsyncBackwardEuler::setTimestep(double timestep) {
  Integrator::setTimestep(timestep);
  if (solver_) solver_->invalidateFactors();
}

void AsyncBackwardEuler::step() {
  maybeRepartition();
  Stopwatch whole;
  const double rebuildBefore = runStats_.setupSeconds + runStats_.rebuildSeconds;
  // Step times come from the step index (t0 = k hL, t1 = (k + 1) hL).
  const detail::StepEnd end = solver_->step(time(), stepEndTime());
  commitStep(end.displacement, end.velocity);
  ++runStats_.steps;
  ++stepsKept_;
  runStats_.stepSeconds += whole.stop() - (runStats_.setupSeconds + runStats_.rebuildSeconds - rebuildBefore);
}

AsyncStepSolver AsyncBackwardEuler::stepSolver() const { return solver_->kind(); }

double AsyncBackwardEuler::solveFloorSeconds(int repeats) {
  if (solver_->kind() == AsyncStepSolver::hierarchy) {
    throw Error("solveFloorSeconds: not measured for the hierarchy solve");
  }
  return static_cast<detail::TwoLevelStepSolver&>(*solver_).solveFloorSeconds(repeats);
}

long long AsyncBackwardEuler::factorNonZeros() const { return solver_->factorNonZeros(); }

const detail::HierarchyStepSolver& AsyncBackwardEuler::hierarchySolver(const char* what) const {
  if (solver_->kind() != AsyncStepSolver::hierarchy) {
    throw Error(std::string("async integrator: ") + what +
                " is defined for the hierarchy solve only (this partition runs the " + toString(solver_->kind()) +
                " solver)");
  }
  return static_cast<const detail::HierarchyStepSolver&>(*solver_);
}

long long AsyncBackwardEuler::stepSystemUnknowns() const {
  return hierarchySolver("stepSystemUnknowns").system().unknowns();
}
bool AsyncBackwardEuler::hierarchyByLevel() const { return hierarchySolver("hierarchyByLevel").system().structured(); }
Eigen::VectorXd AsyncBackwardEuler::stepVelocities(int freeDof) const {
  return hierarchySolver("stepVelocities").system().velocities(freeDof);
}
Eigen::VectorXd AsyncBackwardEuler::stepDisplacements(int freeDof) const {
  return hierarchySolver("stepDisplacements").system().displacements(freeDof);
}

}  // namespace asyncfem
