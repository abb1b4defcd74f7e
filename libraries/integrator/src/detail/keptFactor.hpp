// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/core/vertexJacobian.hpp>
#include <asyncfem/sparseSolver/factorReusingSolver.hpp>
#include <string>

// Backward Euler's kept factor (IntegratorOptions::reuseFactor) as checkpoints hold it:
// not the factor, but what it was computed from, so that a resumed run factors the same
// matrix once and continues bit for bit without refactoring at every frame.
namespace asyncfem::detail {

/// How the system matrix that the kept factor belongs to was assembled (BackwardEuler):
///
/// - step:   w_M M + w_K K_s (+ contact blocks), the step formula's weights at `timestep`,
///           K_s the tangent at stepStart (nonlinear models; a linear model's constant K
///           when stepStart is empty);
/// - newton: (1 + h alpha) M + h beta K_D + h^2 K(iterate) (+ contact blocks), K_D =
///           K(iterate) when dampingAtIterate, else K(stepStart).
///
/// contact: the implicit contact blocks added (h^2 K_c + h C_c), empty when none were.
struct KeptMatrix {
  enum class Kind { none = 0, step = 1, newton = 2 };
  Kind kind = Kind::none;
  double timestep = 0.0;
  Eigen::VectorXd stepStart;  ///< full u (3n) of K_s; empty: a linear model's constant K
  Eigen::VectorXd iterate;    ///< full u (3n) of the Newton iterate (newton only)
  bool dampingAtIterate = false;
  VertexJacobian contact;
};

/// Everything a BackwardEuler with a kept factor carries from one step to the next beyond
/// (u, v, t): the reuse rule's state, the kept factor's matrix (kind none when the rule
/// needs none: no factor yet, or a refactorization already due) and the last solve's
/// solution, where the next PCG starts.
struct KeptFactorState {
  FactorReuseRuleState rule;
  KeptMatrix matrix;
  Eigen::VectorXd previousSolution;  ///< dv of the last step (free DOFs), or empty
};

/// What BackwardEuler tracks of its system matrix for the kept factor's record: how the
/// matrix assembled last was built, and the matrix of the factor kept now.
struct KeptFactorRecord {
  KeptMatrix::Kind assembledKind = KeptMatrix::Kind::none;  ///< free system matrix's last assembly
  bool assembledWithContact = false;
  bool assembledDampingAtIterate = false;
  KeptMatrix kept;  ///< kind none: no factor yet
  /// setInternalState() got no state (a checkpoint from before the kept factor was in
  /// checkpoints): the resumed run refactored instead, and says so (RunReport::resumeCaveat).
  bool restoredWithoutState = false;
};

/// The state as Integrator::internalState() returns it: a versioned vector of doubles
/// (counts and flags stored exactly), layout in keptFactor.cpp.
Eigen::VectorXd encodeKeptFactorState(const KeptFactorState& state);

/// Sizes a decoded state must fit.
struct KeptFactorShape {
  Eigen::Index numDofs = 0;  ///< 3n
  Eigen::Index numFree = 0;  ///< free DOFs
  bool linear = false;       ///< a linear model: stepStart must be empty
};

/// Reads encodeKeptFactorState()'s vector; throws asyncfem::Error naming `who` when it is
/// not one for this shape (size, layout version, flags, counts, vertex indices, values).
KeptFactorState decodeKeptFactorState(const Eigen::VectorXd& encoded, const KeptFactorShape& shape,
                                      const std::string& who);

}  // namespace asyncfem::detail
