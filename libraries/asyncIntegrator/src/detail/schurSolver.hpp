// SPDX-License-Identifier: BSD-3-Clause
// The large-step system of the asynchronous integrator after the fast regions are
// eliminated: H^{LL*} = Â^L - sum_i C_i on the interface blocks I_i x I_i. Private to
// the library.
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <asyncfem/asyncIntegrator/asyncOptions.hpp>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <functional>
#include <memory>
#include <vector>

#include "detail/fastRegion.hpp"
#include "detail/wholeSystemFactor.hpp"

namespace asyncfem::detail {

/// Columns of one length in storage that outlives them: shaping it for other columns
/// (a new partition's |L|) reuses the memory already there, so a re-partition on the quick
/// set-up neither frees the last partition's deflation space nor faults a new one in
/// (2 |L| x kept doubles, up to 64 MiB in all). Not initialized.
class ColumnStore {
 public:
  /// Room for `columns` columns of `rows` doubles. The first `kept` columns keep their
  /// values when rows is unchanged; the others are undefined.
  void shape(Eigen::Index rows, Eigen::Index columns, Eigen::Index kept);
  /// Frees the storage.
  void release();
  Eigen::Index rows() const { return rows_; }
  Eigen::Index columns() const { return columns_; }
  Eigen::Map<Eigen::MatrixXd> leftCols(Eigen::Index count) { return {data_.get(), rows_, count}; }
  Eigen::Map<Eigen::VectorXd> col(Eigen::Index k) { return {data_.get() + k * rows_, rows_}; }

 private:
  std::unique_ptr<double[]> data_;
  std::size_t capacity_ = 0;
  Eigen::Index rows_ = 0, columns_ = 0;
};

/// Factors H^{LL*} in one of three strategies (SchurMode) and solves with it; with a
/// factor kept from an earlier tangent, solves the current Schur system by preconditioned
/// refinement (AsyncOptions::KeptFactors::laggedSchur); or, before any factor of its own, borrows the
/// whole single-rate system's factor as preconditioner (AsyncOptions::KeptFactors::quickSetUp).
class SchurSolver {
 public:
  using SparseMatrix = Eigen::SparseMatrix<double>;
  /// out = H^{LL*} y for the current blocks (|L| entries each).
  using Operator = std::function<void(const Eigen::VectorXd& y, Eigen::VectorXd& out)>;
  /// What one refine() did.
  struct Refinement {
    bool converged = false;
    int iterations = 0;     ///< preconditioned iterations after the first solve
    double residual = 0.0;  ///< final relative residual
    bool zeroRightHandSide = false;
  };

  /// Factors H^{LL*} from largeSystem (Â^L, |L| x |L|) and the regions' corrections C_i.
  /// requested is the user's mode; the stable coupling's symmetric H^{LL*} (asymmetry of
  /// the C_i at most 1e-10) is factored by Cholesky, and lowRank falls back to lu when
  /// W = (A^L)^{-1} U would exceed 512 MiB. Adds to stats.
  void factor(const SparseMatrix& largeSystem, const RegionPartition& partition, const std::vector<FastRegion>& regions,
              SchurMode requested, AsyncCoupling coupling, double asymmetry, IntegratorStats& stats);
  /// solution = (H^{LL*})^{-1} rhs with the last factor.
  void solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution);
  /// The preconditioner of refine(): the factor's solveApproximately() in symmetric mode
  /// (CHOLMOD: a single-precision copy of the factor; an external solver: one multigrid
  /// cycle instead of iterating to its tolerance), solve() otherwise.
  void precondition(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution);
  /// x <- T x (transpose: T^T x) on vectors of |L| entries, orthogonal.
  using Transform = std::function<void(Eigen::VectorXd& x, bool transpose)>;
  /// From now until the next factor(), precondition() applies T P T^T with P the last
  /// factor's inverse (T orthogonal, so still symmetric positive definite): the lagged
  /// factor turned with the body (VertexRotations). Empty: P alone.
  void setPreconditionerTransform(Transform transform) { transform_ = std::move(transform); }
  /// H^{LL*} solution = rhs for the operator of the current blocks, with the last factor as
  /// preconditioner (laggedSchur): conjugate gradients when symmetric (the stable coupling),
  /// iterative refinement otherwise, to a relative residual of tolerance in at most
  /// maxIterations iterations. Not converged: the caller then refactors. A slow convergence
  /// (more than half the iterations) asks for a refactor at the next step
  /// (refreshRequested()).
  ///
  /// track (may be empty) follows the solution through the operator's side products:
  /// track(1, true) right after apply() was called with the whole current solution, and
  /// track(step, false) after the solution moved by step times the direction apply() was
  /// last called with. So a caller can keep any linear image of the solution that apply()
  /// computes on the way (the regions' substitutions of H^{SL} Y) without computing it again.
  using Tracker = std::function<void(double coefficient, bool reset)>;
  Refinement refine(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution, const Operator& apply, bool symmetric,
                    int maxIterations, double tolerance, const Tracker& track = {});

  /// Until the next factor() or reset(), solve() applies the inverse of the Schur
  /// complement of the whole single-rate system on L (largeDofs: global ids of L) instead
  /// of a factor of H^{LL*}: exact when every ratio is 1, a preconditioner otherwise.
  /// whole must outlive the borrowing.
  void borrow(WholeSystemFactor* whole, std::vector<int> largeDofs);
  bool borrowing() const { return borrowed_ != nullptr; }
  /// H^{LL*} solution = rhs by deflated conjugate gradients (Eq. Q3) on the borrowed
  /// preconditioner: the directions of earlier solves with the same operator (at most
  /// `keep`) are projected out, so each solve needs fewer iterations than the one before.
  /// Each iteration is one preconditioner solve and one product with H^{LL*}.
  Refinement solveDeflated(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution, const Operator& apply,
                           int maxIterations, double tolerance, int keep);
  /// Drops the kept directions (the operator changed).
  void forgetDirections() { kept_ = 0; }
  int keptDirections() const { return kept_; }

  /// Forgets the pattern, the analysis, the factor and the deflation directions (a new
  /// partition). Keeps the external solver's factory and the directions' storage; the old
  /// factor's memory is released by the next factor().
  void reset();
  /// From the next factor() on, H^{LL*} is assembled (symmetric mode) and factored by the
  /// solver factory(largeDofs, interfaceDofs) returns (AsyncOptions::Processes::largeSystemSolver);
  /// empty: CHOLMOD.
  void useExternalSolver(AsyncOptions::Processes::LargeSystemSolverFactory factory, std::vector<int> largeDofs,
                         std::vector<std::vector<int>> interfaceDofs);
  SchurMode modeUsed() const { return modeUsed_; }
  bool factored() const { return factored_; }
  /// Whether the last refine() converged slowly; cleared by the next factor().
  bool refreshRequested() const { return refreshNext_; }
  const SparseSolver* solver() const { return solver_.get(); }

 private:
  void chooseSolver(SchurMode mode);
  /// precondition() without the transform.
  void applyPreconditioner(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution);
  /// One conjugate-gradient update from z = correction_ and r = residual_ (rz carries
  /// r.z between calls); deflated: the direction is made H-orthogonal to the kept ones.
  /// Returns the direction's curvature p.Hp (not positive: nothing was updated).
  double conjugateStep(Eigen::VectorXd& solution, const Operator& apply, bool first, bool deflated, double& rz);
  void factorLowRank(const SparseMatrix& largeSystem, const RegionPartition& partition,
                     const std::vector<FastRegion>& regions, const std::vector<int>& interfaceUnion,
                     IntegratorStats& stats);
  void buildPattern(const SparseMatrix& largeSystem, const RegionPartition& partition);
  void factorAssembled(const SparseMatrix& largeSystem, const RegionPartition& partition,
                       const std::vector<FastRegion>& regions, IntegratorStats& stats);

  SchurMode modeUsed_ = SchurMode::lowRank;
  AsyncOptions::Processes::LargeSystemSolverFactory external_;
  std::vector<int> externalLarge_;
  std::vector<std::vector<int>> externalInterfaces_;
  WholeSystemFactor* borrowed_ = nullptr;
  std::vector<int> borrowedLarge_;  // global ids of L (a copy: the set-up may be cached)
  // Deflation space of solveDeflated: columns [0, kept_) of directions_ (W, H^{LL*}-
  // orthonormal) and of their products (H^{LL*} W).
  // Kept by reset().
  ColumnStore directions_, productsOfDirections_;
  int kept_ = 0;
  Eigen::VectorXd coefficients_;
  std::unique_ptr<SparseSolver> solver_;  // of H^{LL*} (lu, symmetric) or of A^L (lowRank)
  bool analyzed_ = false;
  bool factored_ = false;
  bool refreshNext_ = false;
  // H^{LL*} on a fixed pattern (A^L's plus every region's dense I_i x I_i block), so a
  // refactor only writes values: where each A^L entry and each block entry sits in it.
  SparseMatrix schur_;
  bool patternBuilt_ = false;
  std::vector<int> fromLarge_;
  std::vector<std::vector<int>> fromBlock_;
  // Low-rank form H^{LL*} = A^L - U C U^T.
  std::vector<int> interfaceUnion_;                   // positions in L of every region's interface DOFs
  Eigen::MatrixXd unionCorrection_;                   // C, q x q
  Eigen::MatrixXd lowRankBasis_;                      // W = (A^L)^{-1} U, |L| x q
  Eigen::PartialPivLU<Eigen::MatrixXd> capacitance_;  // I - U^T W C
  Eigen::MatrixXd solution_;
  Eigen::VectorXd product_, residual_, correction_, direction_, previousResidual_;
  Transform transform_;             // of the preconditioner, until the next factor()
  const Tracker* track_ = nullptr;  // refine()'s, while it runs
  Eigen::VectorXd turned_;
  // The previous partition's solver, kept by reset() until the next factor() frees it.
  std::unique_ptr<SchurSolver> retired_;
};

}  // namespace asyncfem::detail
