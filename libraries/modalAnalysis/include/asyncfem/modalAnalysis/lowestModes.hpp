// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <limits>
#include <memory>

namespace asyncfem {

/// The matrices whose modes describe a scene's small vibrations about the rest shape.
struct VibrationMatrices {
  Eigen::SparseMatrix<double> stiffness;  ///< linear FEM K (3n x 3n)
  Eigen::SparseMatrix<double> mass;       ///< M of the requested type (3n x 3n)
};
/// K and M of the mesh with its materials, on one assembler's pattern (hexahedra: hexElements'
/// assembly). For a corotational scene, K is its tangent at the rest shape (corotational FEM
/// linearises to linear FEM there).
VibrationMatrices vibrationMatrices(const TetMesh& mesh, MassType massType);

/// Settings of lowestModes().
struct ModalOptions {
  int count = 10;  ///< number of modes K, 0 < K < free DOFs
  /// Shift sigma of the shift-invert transformation (1/s^2): the solver factors K - sigma M
  /// once and finds the eigenvalues nearest sigma. NaN (default): sigma = -1e-8 max_i K_ii / M_ii,
  /// a small negative shift (below every eigenvalue, so K - sigma M is positive definite even
  /// for a free-floating body with its six zero modes, and Cholesky applies) whose size keeps
  /// the condition number of K - sigma M near 1e8-1e9, so the solves stay accurate.
  double shift = std::numeric_limits<double>::quiet_NaN();
  /// Factorization of K - sigma M: Cholesky needs sigma below the lowest eigenvalue; a
  /// shift inside the spectrum needs an indefinite solver (umfpack, eigen-lu).
  SolverKind solver = SolverKind::cholmod;
  double tolerance = 1e-10;  ///< relative tolerance on the Ritz values (Spectra's tol)
  int maxIterations = 1000;  ///< implicit restarts at most
};

/// The K lowest modes of K phi = lambda M phi on the free DOFs.
struct ModalResult {
  Eigen::VectorXd eigenvalues;  ///< lambda_j = omega_j^2 (1/s^2), ascending; K entries
  /// omega_j = sqrt(max(lambda_j, 0)) (rad/s), ascending; rigid modes give about 0.
  Eigen::VectorXd frequencies;
  /// 3n x K: full displacement vectors, fixed DOFs zero, M-orthonormal
  /// (phi_i^T M phi_j = delta_ij).
  Eigen::MatrixXd modes;
  double shift = 0.0;            ///< the shift sigma used (1/s^2)
  int iterations = 0;            ///< implicit restarts of the Lanczos iteration
  int operatorApplications = 0;  ///< solves with K - sigma M
  double factorSeconds = 0.0;    ///< factorization of K - sigma M
  double solveSeconds = 0.0;     ///< whole eigensolve, factorization included
};

/// The count lowest eigenpairs of the generalized problem K phi = lambda M phi restricted
/// to the free DOFs, by the implicitly restarted Lanczos method in shift-invert mode
/// (Spectra's SymGEigsShiftSolver): one sparse factorization of K_ff - sigma M_ff and one
/// back-substitution per Lanczos vector, no dense n x n matrix, so it scales like a few
/// implicit timesteps. stiffness and mass: full 3n x 3n symmetric (both triangles stored),
/// M positive definite on the free DOFs.
///
/// Throws asyncfem::ValidationError when count <= 0 or count >= free DOFs, or the sizes do
/// not match; asyncfem::NumericalError when the factorization fails (shift not below the
/// spectrum with Cholesky) or the iteration does not converge (the message says how many
/// of the count modes converged).
ModalResult lowestModes(const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass,
                        const FreeDofs& freeDofs, const ModalOptions& options = {});

/// lowestModes() for several counts on one factorization: the constructor factors
/// K_ff - sigma M_ff once, and every compute(count) runs the Lanczos iteration with that
/// factor (one back-substitution per Lanczos vector), so asking for more modes after a
/// first answer costs solves, not another factorization. The matrices must outlive the
/// solver. Throws as lowestModes() does (the count is checked by compute()).
class LowestModesSolver {
 public:
  LowestModesSolver(const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass,
                    const FreeDofs& freeDofs, const ModalOptions& options = {});
  ~LowestModesSolver();
  LowestModesSolver(const LowestModesSolver&) = delete;
  LowestModesSolver& operator=(const LowestModesSolver&) = delete;

  /// The count lowest modes (options.count is ignored here), as lowestModes() gives them
  /// (the same numbers for the same options and count); the result's factorSeconds is 0
  /// (the factor was made before) and its solveSeconds and operatorApplications are this
  /// call's.
  ModalResult compute(int count) const;

  int numFree() const;
  double shift() const;
  double factorSeconds() const;      ///< the one factorization of K - sigma M
  int operatorApplications() const;  ///< solves with the factor, over every compute()

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace asyncfem
