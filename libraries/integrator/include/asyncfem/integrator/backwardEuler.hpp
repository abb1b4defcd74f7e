// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/integrator/integratorOptions.hpp>
#include <asyncfem/sparseSolver/factorReusingSolver.hpp>
#include <memory>
#include <string>

namespace asyncfem {

namespace detail {
class FreeSystem;
class LowRankContactSolver;
struct KeptFactorRecord;
struct KeptMatrix;
}  // namespace detail

/// Implicit backward Euler on the free DOFs (paper Eq. 5; shared design note, section
/// "Single-rate implicit backward Euler"). One step of size h from (u_k, v_k):
///
///     (M + h D + h^2 K) dv = h ( f_ext(t_{k+1}) - f_int(u_k) - D v_k - h K v_k )
///     v_{k+1} = v_k + dv,   u_{k+1} = u_k + h v_{k+1}
///
/// with D = alpha M + beta K. Since D is a combination of M and K, the system matrix is
/// assembled as (1 + h alpha) M + (h beta + h^2) K and D v as alpha M v + beta K v: no
/// damping matrix is ever formed (with alpha = beta = 0 the damping products are skipped
/// too; stats().skipped says so).
///
/// Linear force model (isLinear()): K is constant, the free system matrix is assembled
/// and factored once (symbolic + numeric) and each step is one back-substitution plus
/// one sparse product with K (and one with M when alpha > 0). setTimestep() triggers one
/// numeric refactorization at the next step.
///
/// Nonlinear force model: each step evaluates f_int(u_k) and K(u_k) once
/// (forcesAndTangent), updates the free matrix values in place and refactors
/// numerically; the symbolic analysis is done once per integrator. With
/// options.maxIterations > 1 the step continues with Newton iterations on the nonlinear
/// backward Euler equations, written for dv with D = alpha M + beta K(u_k) fixed over the
/// step:
///
///     R(dv) = M dv - h ( f_ext(t_{k+1}) - f_int(u_k + h (v_k + dv)) - D (v_k + dv) )
///     J(dv) = M + h D + h^2 K(u_k + h (v_k + dv))
///
/// The first iteration is the linearized step above; iteration i > 1 solves
/// J dv_delta = -R and stops once |R|_2 <= tolerance * |b_0|_2, b_0 the right-hand side
/// of the linearized step (the residual of the linearized equations at dv = 0).
///
/// Line search (options.lineSearch, used when maxIterations > 1): R is the gradient of
/// the incremental potential
///     Phi(dv) = 1/2 dv^T M dv + E(u_k + h (v_k + dv)) - h f_ext^T dv + h dv^T D (v_k + dv/2),
/// E the force model's elastic energy, so every update (the linearized step included) is
/// scaled by t = 1, 1/2, 1/4, ... until Phi decreases enough (Armijo, 1e-4 of the
/// predicted decrease): a step too large for Newton's model is shortened instead of
/// diverging. Each trial costs one energy evaluation.
///
/// Rayleigh damping under Newton: by default D keeps K(u_k) of the step start (the step
/// equations stay a potential's gradient). options.rayleighStiffnessAtIterate uses
/// D = alpha M + beta K(u_{k+1}^{(i)}) in R and J at every iterate, as Vega FEM does; the
/// line search then acts on the linearized first update only (the later ones solve
/// equations that are no potential's gradient and are taken in full, as in Vega).
///
/// Implicit external force (DynamicSystem::externalForceJacobian set, e.g. penalty contact
/// with contact.implicit): the step solves the backward Euler equations with the force at
/// the step's end state,
///
///     R(dv) = M dv - h ( f(u_{k+1}, v_{k+1}) - f_int(u_{k+1}) - D v_{k+1} ) = 0,
///
/// by Newton from the predicted state (u_k + h v_k, v_k): the first solve is the linearized
/// step with the force and its per-vertex blocks K_c = -df/du, C_c = -df/dv taken at the
/// prediction, f ~ f_p - (h K_c + C_c) dv, i.e. h^2 K_c + h C_c added to the step matrix
/// (their symmetric positive semi-definite part, so the matrix stays one for Cholesky).
/// Whenever the prediction or a result has vertices in contact, Newton continues with the
/// force and blocks at each iterate until |R| <= tolerance * max(|b_0|, h |f_p|), at most
/// max(maxIterations, contactIterations) iterations (a nonlinear model with maxIterations = 1
/// keeps its elastic force linearized at u_k, f_int(u_k) + K(u_k)(u_{k+1} - u_k), so only the
/// contact iterates: the linearized step asked for, with implicit contact); an update that raises |R| is halved
/// back (up to 8 times); a step that stops unconverged is counted (report()), and one whose
/// relative residual is then above 1 throws NumericalError. Exact for a frictionless plane
/// once the contact set settles; a stiff spring (omega h >> 2) stays stable where an explicit
/// one adds energy at impacts. Linear models keep M + h D + h^2 K factored and solve a step
/// with contact by a low-rank (Woodbury) update of that factor where cheaper
/// (options.contactLowRank), else with the step's own matrix (kept-factor PCG under
/// options.reuseFactor, or a factorization). With DynamicSystem::externalForceCoupledJacobian
/// (surface contact) a linear model takes each pair as one rank-one coupling, its
/// off-diagonal blocks included, in that low-rank update; a solve with the step's own
/// matrix, and every nonlinear model, takes the pairs' per-vertex bounds instead
/// (boundCouplings: the pattern has no off-diagonal blocks between bodies), with which
/// Newton converges only linearly. The line search is off with implicit contact
/// (contact damping is no potential's gradient).
///
/// options.reuseFactor (nonlinear models, the default): the system matrix is still
/// assembled at every step, but solved by a FactorReusingSolver: PCG to
/// options.pcgTolerance preconditioned by the last numeric factor, refactoring when the
/// iteration count says the factor is stale. The kept factor outlives frames: what it
/// depends on is internalState() (how its matrix was assembled: the displacements of its
/// tangents, its timestep and contact blocks; the reuse rule's counters; the last solution,
/// where the next PCG starts), so a run resumed from a checkpoint factors that matrix once
/// and continues bit for bit. Its counters are factorReuseStats(); refactorizations are
/// also counted in stats().factorizations.
class BackwardEuler final : public Integrator {
 public:
  /// system: validated; h > 0. Factors at once for linear force models.
  BackwardEuler(DynamicSystem system, double timestep, const IntegratorOptions& options = {});
  ~BackwardEuler() override;

  std::string name() const override { return "backward-euler"; }
  void step() override;
  void setTimestep(double timestep) override;
  /// With a kept factor (reuseFactor; empty otherwise): the reuse rule's state, how the
  /// kept factor's matrix was assembled and the last step's dv (detail/keptFactor.hpp has
  /// the layout), so that setInternalState() continues bit for bit.
  Eigen::VectorXd internalState() const override;
  /// Restores internalState(): factors the kept factor's matrix again, rebuilt from the
  /// displacements, timestep and contact blocks it was assembled from. An empty vector (a
  /// checkpoint written before format version 3) refactors at the next step instead, and
  /// report().resumeCaveat says so. Throws asyncfem::Error for a vector that is not such a
  /// state of this integrator.
  void setInternalState(const Eigen::VectorXd& state) override;

  const IntegratorOptions& options() const { return options_; }
  /// Newton iterations (factorizations) used by the last step: 1 for the linearized step.
  int lastIterations() const { return lastIterations_; }
  /// |R|_2 / |b_0|_2 after the last step's final iteration, or -1 when it was not
  /// evaluated (linear models and maxIterations = 1 never evaluate it: the linearized
  /// step is taken as is).
  double lastRelativeResidual() const { return lastRelativeResidual_; }
  /// Step halvings the line search made during the last step (0: every full Newton
  /// update was accepted, or no line search).
  int lastLineSearchHalvings() const { return lastLineSearchHalvings_; }
  /// PCG and refactorization counters when options().reuseFactor is in effect, else null.
  const FactorReuseStats* factorReuseStats() const;
  /// The factor non-zeros and, for nonlinear models, a summary line saying which linear
  /// solve path ran (exact factorizations, or the kept factor with its counts).
  RunReport report() const override;
  /// True: DynamicSystem::externalForceJacobian is used (see the class comment).
  bool linearizesExternalForce() const override { return true; }

 private:
  void stepLinear();
  void stepNonlinear();
  /// u_, v_ = the free state; force = f_ext(t_{k+1}) on the free DOFs (zero without one).
  void restrictStepStart(Eigen::VectorXd& force);
  /// v += dv, u += h v, and the step committed.
  void finishStep();
  /// Newton iterations after the linearized step (options_.maxIterations > 1): returns
  /// how many were taken in all, counting the linearized one.
  int newtonIterations(double rhsNorm, Eigen::VectorXd& internal);
  /// Linear model: solution = A^{-1} rhs, A = M + h D + h^2 K plus contact_'s blocks.
  void solveLinearStep(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution);
  /// solution = A^{-1} rhs with A assembled with contact_'s blocks and solved as it stands
  /// (kept-factor PCG under reuseFactor, else factored).
  void solveWithContactMatrix(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution);
  /// Implicit contact with the elastic force linear in the step (a linear model, or the
  /// linearized step of a nonlinear one: startInternal = f_int(u_k) on the free DOFs, K(u_k)
  /// in free_->stiffness): Newton iterations after the first solve, returns the solves made.
  int linearContactIterations(double rhsNorm, bool solvedWithContact, const Eigen::VectorXd* startInternal);
  /// Records the relative residual; true when the contact iterations stop (converged, or
  /// at the allowed count: counted as unconverged). Throws NumericalError when not finite.
  bool stopContactIterations(double relativeResidual, int iterations, int allowed);
  /// When the last contact Newton update (correction, of which contactStepFraction_ is
  /// applied) raised the residual: moves dv_ back to half that fraction and returns true
  /// (the caller evaluates again). false: accept, take a new update.
  bool retreatContactStep(double relativeResidual, int iterations, int allowed, const Eigen::VectorXd& correction);
  /// What contact iterations' residuals are relative to: max(|b_0|, h |f_ext(prediction)|).
  double contactResidualScale(double rhsNorm) const;
  /// residual = R(dv) at the iterate (internal forces f_int(u_{k+1}), free).
  void iterateResidual(const Eigen::VectorXd& internal, const Eigen::SparseMatrix<double>& dampingStiffness,
                       const Eigen::VectorXd& newVelocity, Eigen::VectorXd& residual);
  /// J correction = -residual with J at the iterate (refactored, or the kept factor).
  void solveNewtonCorrection(const Eigen::SparseMatrix<double>& dampingStiffness, const Eigen::VectorXd& residual,
                             Eigen::VectorXd& correction);
  /// free_->systemMatrix = the step formula's (A1) combination of M and K, plus the
  /// implicit contact blocks of contact_ when withContact.
  void assembleSystemMatrix(bool withContact);
  /// free_->systemMatrix = w_M M + w_K free_->stiffness at timestep h, plus contact's blocks.
  void assembleStepMatrix(double h, const VertexJacobian& contact);
  /// free_->systemMatrix = (1 + h alpha) M + h beta damping + h^2 free_->iterateStiffness,
  /// plus contact's blocks (a Newton iteration's J).
  void assembleNewtonMatrix(double h, const Eigen::SparseMatrix<double>& damping, const VertexJacobian& contact);
  /// free_->systemMatrix += h^2 K_c + h C_c (contact's blocks).
  void addContactBlocks(double h, const VertexJacobian& contact);
  /// The reuse solver just factored free_->systemMatrix: records how it was assembled.
  void recordKeptMatrix();
  /// free_->systemMatrix = the kept factor's matrix, assembled again as recorded.
  void rebuildKeptMatrix(const detail::KeptMatrix& kept);
  /// force (free) = f_ext(t_{k+1}) at the full state (u, v), and contact_ = its Jacobian there.
  void evaluateImplicitExternalForce(const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                                     Eigen::VectorXd& force);
  void assembleAndFactor();
  // Incremental potential Phi(dv) of the current step (see the class comment).
  double incrementalPotential(const Eigen::VectorXd& dv);
  // Step length t in (0, 1] along step from dv by backtracking on Phi.
  double backtrack(const Eigen::VectorXd& dv, const Eigen::VectorXd& step, double potential, double slope);
  // With options_.reuseFactor: hands the assembled system matrix to reuse_ (refactoring
  // only when it asks to) and solves with it; the time goes to the same stats fields.
  void assembleForReuse();
  void updateReusedMatrix();
  void solveWithReuse(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution);

  IntegratorOptions options_;
  std::unique_ptr<detail::FreeSystem> free_;
  std::unique_ptr<FactorReusingSolver> reuse_;            // options_.reuseFactor, nonlinear models only
  std::unique_ptr<detail::KeptFactorRecord> keptRecord_;  // with reuse_: how its factor's matrix was assembled
  bool linear_ = false;
  bool factorizationStale_ = true;
  bool implicitExternal_ = false;        // system_.externalForceJacobian is set
  bool factorHasContact_ = false;        // linear model: free_'s factor holds contact blocks
  bool coupledContact_ = false;          // linear model: contact_ from externalForceCoupledJacobian (couplings)
  long long boundedCouplingSolves_ = 0;  // contact solves that took the couplings' per-vertex bounds
  VertexJacobian contact_;               // the external force's Jacobian at the last evaluation
  long long contactSteps_ = 0;           // steps whose prediction had vertices in contact
  std::unique_ptr<detail::LowRankContactSolver> lowRank_;  // linear models: Woodbury updates of the kept factor
  long long lowRankSolves_ = 0;
  long long unconvergedContactSteps_ = 0;
  long long residualSteps_ = 0;       // steps whose contact iterations evaluated a residual
  long long residualStepSolves_ = 0;  // the solves those steps took
  double largestUnconvergedResidual_ = 0.0;
  double contactPreviousResidual_ = 0.0;  // backtracking of the contact Newton updates
  double contactStepFraction_ = 1.0;
  int contactHalvings_ = 0;
  double predictedImpulse_ = 0.0;  // h |f_ext| at the prediction (implicit contact)
  int lastIterations_ = 0;
  double lastRelativeResidual_ = -1.0;
  int lastLineSearchHalvings_ = 0;
  // Scratch on the free DOFs, kept to avoid per-step allocation.
  Eigen::VectorXd u_, v_, force_, rhs_, dv_, work_;
  Eigen::VectorXd fullForce_, fullU_, fullV_, fullPredicted_;
};

}  // namespace asyncfem
