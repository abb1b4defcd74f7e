// SPDX-License-Identifier: BSD-3-Clause
#include <petscksp.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/integrator/stepFormula.hpp>
#include <asyncfem/petscBackend/petscSimulation.hpp>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include "detail/distributedSystem.hpp"
#include "detail/linearSolver.hpp"
#include "detail/petscCall.hpp"
#include "detail/petscHandle.hpp"

namespace asyncfem {

using detail::checkPetsc;
using detail::collectively;

std::string toString(PetscIntegratorKind kind) {
  return kind == PetscIntegratorKind::backwardEuler ? "backward-euler" : "trapezoidal";
}

std::string toString(PetscForceModelKind kind) {
  switch (kind) {
    case PetscForceModelKind::linear:
      return "linear";
    case PetscForceModelKind::corotational:
      return "corotational";
    case PetscForceModelKind::stvk:
      return "stvk";
    case PetscForceModelKind::neoHookean:
      return "neo-hookean";
    case PetscForceModelKind::mooneyRivlin:
      return "mooney-rivlin";
  }
  return "unknown";
}

PetscIntegratorKind parsePetscIntegratorKind(const std::string& name) {
  for (PetscIntegratorKind kind : {PetscIntegratorKind::backwardEuler, PetscIntegratorKind::trapezoidal}) {
    if (toString(kind) == name) return kind;
  }
  throw ValidationError("unknown PETSc backend integrator '" + name + "' (expected backward-euler or trapezoidal)");
}

PetscForceModelKind parsePetscForceModelKind(const std::string& name) {
  for (PetscForceModelKind kind :
       {PetscForceModelKind::linear, PetscForceModelKind::corotational, PetscForceModelKind::stvk,
        PetscForceModelKind::neoHookean, PetscForceModelKind::mooneyRivlin}) {
    if (toString(kind) == name) return kind;
  }
  throw ValidationError("unknown PETSc backend force model '" + name +
                        "' (expected linear, corotational, stvk, neo-hookean or mooney-rivlin)");
}

namespace {

/// Throws ValidationError on every rank for settings the backend cannot run with.
void validateSettings(MPI_Comm comm, const TetMesh& mesh, const PetscSimulationSettings& settings) {
  collectively(comm, [&] {
    if (!(settings.timestep > 0.0) || !std::isfinite(settings.timestep)) {
      throw ValidationError("PETSc backend: the timestep must be finite and > 0 (got " +
                            std::to_string(settings.timestep) + ")");
    }
    if (!(settings.rayleighMass >= 0.0) || !(settings.rayleighStiffness >= 0.0)) {
      throw ValidationError("PETSc backend: Rayleigh damping coefficients must be >= 0");
    }
    if (!settings.gravity.allFinite()) throw ValidationError("PETSc backend: gravity is not finite");
    if (settings.constantForce.size() != 0 && settings.constantForce.size() != mesh.numDofs()) {
      throw ValidationError("PETSc backend: the constant force has " + std::to_string(settings.constantForce.size()) +
                            " values, expected 3 x " + std::to_string(mesh.numVertices()));
    }
    for (Eigen::Index i = 0; i < settings.constantForce.size(); ++i) {
      if (!std::isfinite(settings.constantForce[i])) {
        throw ValidationError("PETSc backend: the constant force is not finite at vertex " + std::to_string(i / 3));
      }
    }
    if (!(settings.solver.relativeTolerance >= 0.0) || settings.solver.maxIterations < 1) {
      throw ValidationError("PETSc backend: the solver needs a relative tolerance >= 0 and maxIterations >= 1");
    }
    if (settings.newton.maxIterations < 1 || !(settings.newton.tolerance >= 0.0)) {
      throw ValidationError("PETSc backend: Newton needs maxIterations >= 1 and a tolerance >= 0");
    }
    if (settings.newton.maxIterations > 1 && settings.integrator == PetscIntegratorKind::trapezoidal &&
        settings.forceModel != PetscForceModelKind::linear) {
      throw ValidationError(
          "PETSc backend: Newton iterations (maxIterations > 1) run with backward-euler only; the trapezoidal "
          "rule takes the linearized step (maxIterations 1)");
    }
  });
}

/// Every rank must hold the same mesh: a cheap signature check before any collective
/// call that depends on its size.
void requireSameMesh(MPI_Comm comm, const TetMesh& mesh) {
  long long signature[2] = {mesh.numVertices(), mesh.numElements()};
  long long low[2] = {0, 0};
  long long high[2] = {0, 0};
  MPI_Allreduce(signature, low, 2, MPI_LONG_LONG, MPI_MIN, comm);
  MPI_Allreduce(signature, high, 2, MPI_LONG_LONG, MPI_MAX, comm);
  if (low[0] != high[0] || low[1] != high[1]) {
    throw ValidationError("PETSc backend: the ranks hold different meshes (vertices " + std::to_string(low[0]) + ".." +
                          std::to_string(high[0]) + ", elements " + std::to_string(low[1]) + ".." +
                          std::to_string(high[1]) + "); every rank must pass the same mesh");
  }
}

}  // namespace

struct PetscSimulation::Impl {
  Impl(const TetMesh& mesh, const PetscSimulationSettings& givenSettings);

  PetscSimulationSettings settings;
  bool trapezoidal = false;
  detail::DistributedSystem body;
  detail::OptionsHandle options;  // declared before the solvers: destroyed after them
  detail::LinearSolver solver;
  std::optional<detail::LinearSolver> massSolver;  // trapezoidal only: M a_0 = ...

  bool systemStale = true;        // system matrix weights or K changed
  bool accelerationStale = true;  // trapezoidal a_k
  double timeOrigin = 0.0;
  long long stepIndex = 0;
  PetscRunStats stats;
  Stopwatch assemblyWatch, solveWatch;

  double time() const { return timeOrigin + (static_cast<double>(stepIndex) * settings.timestep); }
  double stepEndTime() const { return timeOrigin + (static_cast<double>(stepIndex + 1) * settings.timestep); }

  /// K(u) and f_int(u) at the current state (nonlinear models); marks the system stale.
  void assembleTangent() {
    body.assembleNonlinear(body.displacement.get(), body.stiffness.get());
    systemStale = true;
  }
  /// The system matrix of the step, if K or the weights changed, handed to the solver.
  void updateSystem(const stepFormula::MatrixWeights& weights) {
    if (!systemStale) return;
    body.combineSystem(weights.mass, weights.stiffness);
    solver.setOperator(body.system.get());
    systemStale = false;
  }
  void buildRightHandSide(const stepFormula::RightHandSide& recipe);
  void solve(detail::LinearSolver& linearSolver, Vec right, Vec solution, const char* what);
  void checkFinite() const;
  void computeAcceleration();
  void stepBackwardEuler();
  int newtonIterations(double rhsNorm);
  void newtonResidual(Vec dv);
  void solveNewtonCorrection();
  double incrementalPotential(Vec dv);
  double backtrack(Vec dv, Vec step, double potential, double slope);
  [[noreturn]] void throwDiverged(double relativeResidual, int iterations);
  void stepTrapezoidal();
  void collectStats(Stopwatch& setup);
};

PetscSimulation::Impl::Impl(const TetMesh& mesh, const PetscSimulationSettings& givenSettings)
    : settings(givenSettings),
      trapezoidal(givenSettings.integrator == PetscIntegratorKind::trapezoidal),
      body(PETSC_COMM_WORLD, mesh, givenSettings),
      options(detail::makeSolverOptions(givenSettings.solver.options)),
      solver(body.comm, options.get(), givenSettings.solver, "", nullptr) {
  if (trapezoidal) massSolver.emplace(body.comm, options.get(), settings.solver, "mass_", body.mass.get());
}

void PetscSimulation::Impl::collectStats(Stopwatch& setup) {
  const detail::DistributedLayout& layout = body.layout;
  stats.ranks = layout.numRanks;
  stats.elementsPerRank = layout.elementsPerRank;
  for (int r = 0; r < layout.numRanks; ++r) {
    const auto i = static_cast<std::size_t>(r);
    stats.freeDofsPerRank.push_back(static_cast<int>(3 * (layout.blockStart[i + 1] - layout.blockStart[i])));
  }
  stats.freeDofs = body.globalDofs();
  MatInfo info;
  checkPetsc(MatGetInfo(body.system.get(), MAT_GLOBAL_SUM, &info), "MatGetInfo");
  stats.matrixNonZeros = static_cast<long long>(info.nz_used);
  stats.kspType = solver.kspType();
  stats.pcType = solver.pcType();
  stats.setupSeconds = setup.stop();
}

void PetscSimulation::Impl::solve(detail::LinearSolver& linearSolver, Vec right, Vec solution, const char* what) {
  ScopedTimer timer(solveWatch);
  const detail::SolveOutcome outcome = linearSolver.solve(right, solution);
  if (!outcome.converged) {
    throw NumericalError("PETSc backend: the " + std::string(what) + " solve of step " + std::to_string(stepIndex + 1) +
                         " (t = " + std::to_string(stepEndTime()) + ") failed: " + outcome.reason + " after " +
                         std::to_string(outcome.iterations) + " iterations");
  }
  ++stats.solves;
  stats.lastIterations = std::max<int>(1, outcome.iterations);
  stats.solverIterations += stats.lastIterations;
}

/// Throws NumericalError on every rank naming the lowest vertex with a non-finite u or v
/// after the step that ends at stepEndTime().
void PetscSimulation::Impl::checkFinite() const {
  const int vertex = body.lowestNonFiniteVertex();
  if (vertex >= 0) {
    throw NumericalError("PETSc backend: non-finite displacement or velocity at vertex " + std::to_string(vertex) +
                         " after step " + std::to_string(stepIndex + 1) + " (t = " + std::to_string(stepEndTime()) +
                         ")");
  }
}

PetscSimulation::PetscSimulation(const TetMesh& mesh, const PetscSimulationSettings& settings) {
  Stopwatch setup;
  validateSettings(PETSC_COMM_WORLD, mesh, settings);
  requireSameMesh(PETSC_COMM_WORLD, mesh);
  impl_ = std::make_unique<Impl>(mesh, settings);
  impl_->collectStats(setup);
}

PetscSimulation::~PetscSimulation() = default;

/// rhs = recipe.scale (f_ext - f_int(u) - K w_K - alpha M w_M), stepFormula::RightHandSide
/// with w_K = velocityStiffness v + accelerationStiffness a and w_M = v + accelerationMass a;
/// for the linear model f_int(u) = K u joins the one product K (u + w_K).
void PetscSimulation::Impl::buildRightHandSide(const stepFormula::RightHandSide& recipe) {
  const double alpha = settings.rayleighMass;
  Vec rhs = body.rhs.get();
  Vec work = body.work.get();
  Vec product = body.product.get();
  checkPetsc(VecCopy(body.externalForce.get(), rhs), "VecCopy");
  if (body.nonlinear) checkPetsc(VecAXPY(rhs, -1.0, body.internalForce.get()), "VecAXPY");
  checkPetsc(VecCopy(body.velocity.get(), work), "VecCopy");
  checkPetsc(VecScale(work, recipe.velocityStiffness), "VecScale");
  if (recipe.accelerationStiffness != 0.0) {
    checkPetsc(VecAXPY(work, recipe.accelerationStiffness, body.acceleration.get()), "VecAXPY");
  }
  if (!body.nonlinear) checkPetsc(VecAXPY(work, 1.0, body.displacement.get()), "VecAXPY");
  checkPetsc(MatMult(body.stiffness.get(), work, product), "MatMult");
  checkPetsc(VecAXPY(rhs, -1.0, product), "VecAXPY");
  if (alpha != 0.0) {
    Vec massed = body.velocity.get();
    if (recipe.accelerationMass != 0.0) {
      checkPetsc(VecWAXPY(work, recipe.accelerationMass, body.acceleration.get(), body.velocity.get()), "VecWAXPY");
      massed = work;
    }
    checkPetsc(MatMult(body.mass.get(), massed, product), "MatMult");
    checkPetsc(VecAXPY(rhs, -alpha, product), "VecAXPY");
  }
  if (recipe.scale != 1.0) checkPetsc(VecScale(rhs, recipe.scale), "VecScale");
}

void PetscSimulation::Impl::computeAcceleration() {
  // The equation of motion at the step start: M a = f_ext(t) - f_int(u) - D v, i.e. the
  // right-hand side with w_K = beta v, w_M = v and no scaling.
  body.evaluateExternalForce(time(), settings.timeDependentForce);
  {
    ScopedTimer timer(assemblyWatch);
    if (body.nonlinear) assembleTangent();
  }
  buildRightHandSide({1.0, settings.rayleighStiffness, 0.0, 0.0});
  solve(*massSolver, body.rhs.get(), body.acceleration.get(), "mass");
  accelerationStale = false;
}

void PetscSimulation::Impl::stepBackwardEuler() {
  // Eq. (A1) through stepFormula::backwardEuler: (system) dv = rhs; v += dv, u += h v.
  const double h = settings.timestep;
  body.evaluateExternalForce(stepEndTime(), settings.timeDependentForce);
  {
    ScopedTimer timer(assemblyWatch);
    if (body.nonlinear) assembleTangent();
    updateSystem(stepFormula::backwardEuler::systemMatrix(h, settings.rayleighMass, settings.rayleighStiffness));
  }
  buildRightHandSide(stepFormula::backwardEuler::rightHandSide(h, settings.rayleighStiffness));
  solve(solver, body.rhs.get(), body.increment.get(), "backward Euler");
  stats.lineSearchHalvings = 0;
  if (body.nonlinear && settings.newton.maxIterations > 1) {
    PetscReal rhsNorm = 0.0;
    checkPetsc(VecNorm(body.rhs.get(), NORM_2, &rhsNorm), "VecNorm");
    stats.newtonIterations += newtonIterations(rhsNorm);
  } else {
    ++stats.newtonIterations;
  }
  checkPetsc(VecAXPY(body.velocity.get(), 1.0, body.increment.get()), "VecAXPY");
  checkPetsc(VecAXPY(body.displacement.get(), h, body.velocity.get()), "VecAXPY");
}

// Newton on the backward Euler step equations after the linearized solve, as the
// single-process BackwardEuler does (its class comment): dv = body.increment,
//   R(dv) = M dv - h ( f_ext - f_int(u_k + h (v_k + dv)) - D (v_k + dv) ),  D = alpha M + beta K(u_k),
//   J = (1 + h alpha) M + h beta K(u_k) + h^2 K(u_k + h (v_k + dv)),
// until |R|_2 <= tolerance |b_0|_2 (b_0 = body.rhs, the linearized right-hand side), each
// update shortened by backtracking on the incremental potential when lineSearch is set.
// Returns the iterations taken, the linearized one included.
int PetscSimulation::Impl::newtonIterations(double rhsNorm) {
  const PetscNewtonSettings& newton = settings.newton;
  Vec dv = body.increment.get();
  Vec correction = body.correction.get();
  if (newton.lineSearch) {
    // The linearized step from dv = 0, its slope from its own right-hand side.
    checkPetsc(VecCopy(dv, correction), "VecCopy");
    PetscScalar slope = 0.0;
    checkPetsc(VecDot(body.rhs.get(), correction, &slope), "VecDot");
    checkPetsc(VecSet(dv, 0.0), "VecSet");
    const double t = backtrack(dv, correction, incrementalPotential(dv), -slope);
    checkPetsc(VecAXPY(dv, t, correction), "VecAXPY");
  }
  const double scale = rhsNorm > 0.0 ? rhsNorm : 1.0;
  for (int iterations = 1;; ++iterations) {
    const bool mayIterate = iterations < newton.maxIterations;
    checkPetsc(VecWAXPY(body.trial.get(), 1.0, body.velocity.get(), dv), "VecWAXPY");
    checkPetsc(VecAYPX(body.trial.get(), settings.timestep, body.displacement.get()), "VecAYPX");
    {
      ScopedTimer timer(assemblyWatch);
      body.assembleNonlinear(body.trial.get(), mayIterate ? body.iterateStiffness.get() : nullptr);
    }
    newtonResidual(dv);
    PetscReal residualNorm = 0.0;
    checkPetsc(VecNorm(body.residual.get(), NORM_2, &residualNorm), "VecNorm");
    const double relative = residualNorm / scale;
    if (relative <= newton.tolerance) return iterations;
    if (!mayIterate) {
      if (!(relative <= 1.0)) throwDiverged(relative, iterations);
      return iterations;
    }
    solveNewtonCorrection();
    if (newton.lineSearch) {
      PetscScalar slope = 0.0;
      checkPetsc(VecDot(body.residual.get(), correction, &slope), "VecDot");
      checkPetsc(VecScale(correction, backtrack(dv, correction, incrementalPotential(dv), slope)), "VecScale");
    }
    checkPetsc(VecAXPY(dv, 1.0, correction), "VecAXPY");
  }
}

// residual = R(dv), with f_int of the iterate u_k + h (v_k + dv) in body.internalForce.
void PetscSimulation::Impl::newtonResidual(Vec dv) {
  const double h = settings.timestep;
  const double alpha = settings.rayleighMass;
  const double beta = settings.rayleighStiffness;
  Vec residual = body.residual.get();
  Vec product = body.product.get();
  Vec newVelocity = body.work.get();
  checkPetsc(MatMult(body.mass.get(), dv, residual), "MatMult");
  checkPetsc(VecAXPY(residual, -h, body.externalForce.get()), "VecAXPY");
  checkPetsc(VecAXPY(residual, h, body.internalForce.get()), "VecAXPY");
  checkPetsc(VecWAXPY(newVelocity, 1.0, body.velocity.get(), dv), "VecWAXPY");
  if (alpha != 0.0) {
    checkPetsc(MatMult(body.mass.get(), newVelocity, product), "MatMult");
    checkPetsc(VecAXPY(residual, h * alpha, product), "VecAXPY");
  }
  if (beta != 0.0) {
    checkPetsc(MatMult(body.stiffness.get(), newVelocity, product), "MatMult");
    checkPetsc(VecAXPY(residual, h * beta, product), "VecAXPY");
  }
}

// J correction = -R with J = (1 + h alpha) M + h beta K(u_k) + h^2 K(iterate).
void PetscSimulation::Impl::solveNewtonCorrection() {
  const double h = settings.timestep;
  {
    ScopedTimer timer(assemblyWatch);
    body.combineSystem(1.0 + (h * settings.rayleighMass), h * settings.rayleighStiffness, body.iterateStiffness.get(),
                       h * h);
    solver.setOperator(body.system.get());
    systemStale = true;  // the next step's matrix is the linearized one again
  }
  checkPetsc(VecCopy(body.residual.get(), body.rhs.get()), "VecCopy");
  checkPetsc(VecScale(body.rhs.get(), -1.0), "VecScale");
  checkPetsc(VecSet(body.correction.get(), 0.0), "VecSet");
  solve(solver, body.rhs.get(), body.correction.get(), "Newton correction");
}

// Phi(dv) = 1/2 dv^T M dv + E(u_k + h (v_k + dv)) - h f_ext^T dv + h dv^T D (v_k + dv / 2),
// D = alpha M + beta K(u_k) (body.trial holds u_k + h (v_k + dv) afterwards).
double PetscSimulation::Impl::incrementalPotential(Vec dv) {
  const double h = settings.timestep;
  Vec trial = body.trial.get();
  Vec work = body.work.get();
  Vec product = body.product.get();
  checkPetsc(VecWAXPY(trial, 1.0, body.velocity.get(), dv), "VecWAXPY");
  checkPetsc(VecAYPX(trial, h, body.displacement.get()), "VecAYPX");
  double energy = 0.0;
  {
    ScopedTimer timer(assemblyWatch);
    energy = body.elasticEnergy(trial);
  }
  const auto dot = [&](Mat matrix, Vec right) {
    PetscScalar value = 0.0;
    checkPetsc(MatMult(matrix, right, product), "MatMult");
    checkPetsc(VecDot(dv, product, &value), "VecDot");
    return static_cast<double>(value);
  };
  checkPetsc(VecWAXPY(work, 0.5, dv, body.velocity.get()), "VecWAXPY");
  double damping = 0.0;
  if (settings.rayleighMass != 0.0) damping += settings.rayleighMass * dot(body.mass.get(), work);
  if (settings.rayleighStiffness != 0.0) damping += settings.rayleighStiffness * dot(body.stiffness.get(), work);
  PetscScalar external = 0.0;
  checkPetsc(VecDot(body.externalForce.get(), dv, &external), "VecDot");
  return (0.5 * dot(body.mass.get(), dv)) + energy - (h * external) + (h * damping);
}

// Armijo backtracking as BackwardEuler::backtrack: the step length t in (0, 1] from dv
// along step, halving t up to 12 times until Phi(dv + t step) <= Phi(dv) + 1e-4 t slope
// (differences below 1e-12 |Phi| count as no increase), else the t of the lowest Phi; a
// slope below that allowance is taken in full, unchecked (converged to rounding).
double PetscSimulation::Impl::backtrack(Vec dv, Vec step, double potential, double slope) {
  constexpr int kMaxHalvings = 12;
  const double roundingAllowance = 1e-12 * std::abs(potential);
  if (std::abs(slope) <= roundingAllowance) return 1.0;
  Vec candidate = body.candidate.get();
  double t = 1.0;
  double bestT = 1.0;
  double bestPotential = std::numeric_limits<double>::infinity();
  for (int halving = 0; halving <= kMaxHalvings; ++halving) {
    checkPetsc(VecWAXPY(candidate, t, step, dv), "VecWAXPY");
    const double trial = incrementalPotential(candidate);
    if (std::isfinite(trial) && trial <= potential + (1e-4 * t * std::min(slope, 0.0)) + roundingAllowance) return t;
    if (std::isfinite(trial) && trial < bestPotential) {
      bestPotential = trial;
      bestT = t;
    }
    ++stats.lineSearchHalvings;
    t *= 0.5;
  }
  return bestPotential < std::numeric_limits<double>::infinity() ? bestT : t;
}

void PetscSimulation::Impl::throwDiverged(double relativeResidual, int iterations) {
  Vec magnitude = body.product.get();
  checkPetsc(VecCopy(body.residual.get(), magnitude), "VecCopy");
  checkPetsc(VecAbs(magnitude), "VecAbs");
  PetscInt largest = 0;
  PetscReal value = 0.0;
  checkPetsc(VecMax(magnitude, &largest, &value), "VecMax");
  const int vertex = largest >= 0 ? body.layout.blockVertex[static_cast<std::size_t>(largest / 3)] : -1;
  throw NumericalError("PETSc backend: Newton's iteration diverged in the step to time " +
                       std::to_string(stepEndTime()) + ": after " + std::to_string(iterations) +
                       " iterations its residual is " + std::to_string(relativeResidual) +
                       " times the step's initial one, largest at vertex " + std::to_string(vertex) +
                       "; enable lineSearch or reduce the step");
}

void PetscSimulation::Impl::stepTrapezoidal() {
  // Eq. (A1t) through stepFormula::trapezoidal: (system) a_{k+1} = rhs;
  // u += h v + h^2/4 (a + a_{k+1}), v += h/2 (a + a_{k+1}).
  namespace trapezoidalRule = stepFormula::trapezoidal;
  const double h = settings.timestep;
  if (accelerationStale) computeAcceleration();
  body.evaluateExternalForce(stepEndTime(), settings.timeDependentForce);
  {
    ScopedTimer timer(assemblyWatch);
    if (body.nonlinear) assembleTangent();
    updateSystem(trapezoidalRule::systemMatrix(h, settings.rayleighMass, settings.rayleighStiffness));
  }
  buildRightHandSide(trapezoidalRule::rightHandSide(h, settings.rayleighStiffness));
  // The previous acceleration is the initial guess of the iterative solvers.
  checkPetsc(VecCopy(body.acceleration.get(), body.increment.get()), "VecCopy");
  solve(solver, body.rhs.get(), body.increment.get(), "trapezoidal");
  ++stats.newtonIterations;
  Vec sum = body.work.get();
  checkPetsc(VecWAXPY(sum, 1.0, body.acceleration.get(), body.increment.get()), "VecWAXPY");  // a + a_{k+1}
  checkPetsc(VecAXPY(body.displacement.get(), h, body.velocity.get()), "VecAXPY");
  checkPetsc(VecAXPY(body.displacement.get(), trapezoidalRule::displacementWeight(h), sum), "VecAXPY");
  checkPetsc(VecAXPY(body.velocity.get(), trapezoidalRule::velocityWeight(h), sum), "VecAXPY");
  checkPetsc(VecCopy(body.increment.get(), body.acceleration.get()), "VecCopy");
}

void PetscSimulation::step() {
  Impl& s = *impl_;
  if (s.trapezoidal) {
    s.stepTrapezoidal();
  } else {
    s.stepBackwardEuler();
  }
  s.checkFinite();
  ++s.stepIndex;
  ++s.stats.steps;
  s.stats.assemblySeconds = s.assemblyWatch.totalSeconds();
  s.stats.solveSeconds = s.solveWatch.totalSeconds();
}

void PetscSimulation::setState(const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity, double time) {
  Impl& s = *impl_;
  collectively(s.body.comm, [&] {
    if (displacement.size() != s.body.numDofs || velocity.size() != s.body.numDofs) {
      throw ValidationError("PETSc backend: setState needs 3n = " + std::to_string(s.body.numDofs) +
                            " values for u and v (got " + std::to_string(displacement.size()) + " and " +
                            std::to_string(velocity.size()) + ")");
    }
    if (!displacement.allFinite() || !velocity.allFinite() || !std::isfinite(time)) {
      throw ValidationError("PETSc backend: setState got non-finite values");
    }
  });
  s.body.scatterOwned(displacement, s.body.displacement.get());
  s.body.scatterOwned(velocity, s.body.velocity.get());
  // A time on the step grid (a checkpoint's) keeps t = k h exactly, so that a resumed run
  // steps through the very times of the uninterrupted one (as Integrator::setState does).
  const double gridSteps = std::round(time / s.settings.timestep);
  const bool onGrid = std::abs(gridSteps) < 1e15 && gridSteps * s.settings.timestep == time;
  s.timeOrigin = onGrid ? 0.0 : time;
  s.stepIndex = onGrid ? static_cast<long long>(gridSteps) : 0;
  s.accelerationStale = true;
}

Eigen::VectorXd PetscSimulation::gatherInternalState() const {
  const Impl& s = *impl_;
  if (!s.trapezoidal || s.accelerationStale) return {};
  return s.body.gather(s.body.acceleration.get());
}

void PetscSimulation::setInternalState(const Eigen::VectorXd& state) {
  Impl& s = *impl_;
  collectively(s.body.comm, [&] {
    if (state.size() != 0 && (!s.trapezoidal || state.size() != s.body.numDofs)) {
      throw ValidationError("PETSc backend: the internal state has " + std::to_string(state.size()) +
                            " values; expected " +
                            (s.trapezoidal ? std::to_string(s.body.numDofs) + " or none" : "none") + " for " +
                            toString(s.settings.integrator));
    }
    if (!state.allFinite()) throw ValidationError("PETSc backend: the internal state is not finite");
  });
  if (state.size() == 0) return;
  s.body.scatterOwned(state, s.body.acceleration.get());
  s.accelerationStale = false;
}

Eigen::VectorXd PetscSimulation::gatherDisplacement() const {
  return impl_->body.gather(impl_->body.displacement.get());
}
Eigen::VectorXd PetscSimulation::gatherVelocity() const { return impl_->body.gather(impl_->body.velocity.get()); }
double PetscSimulation::time() const { return impl_->time(); }
double PetscSimulation::timestep() const { return impl_->settings.timestep; }
int PetscSimulation::rank() const { return impl_->body.layout.rank; }
int PetscSimulation::numRanks() const { return impl_->body.layout.numRanks; }
const std::vector<int>& PetscSimulation::localElements() const { return impl_->body.layout.localElements; }
const PetscRunStats& PetscSimulation::stats() const { return impl_->stats; }

PetscTrajectory runPetscSimulation(const TetMesh& mesh, const PetscSimulationSettings& settings, int numSteps) {
  if (numSteps < 0)
    throw ValidationError("PETSc backend: numSteps must be >= 0 (got " + std::to_string(numSteps) + ")");
  PetscSimulation simulation(mesh, settings);
  PetscTrajectory trajectory;
  for (int k = 0; k < numSteps; ++k) {
    simulation.step();
    Eigen::VectorXd displacement = simulation.gatherDisplacement();
    if (simulation.rank() == 0) trajectory.displacements.push_back(std::move(displacement));
  }
  trajectory.stats = simulation.stats();
  return trajectory;
}

}  // namespace asyncfem
