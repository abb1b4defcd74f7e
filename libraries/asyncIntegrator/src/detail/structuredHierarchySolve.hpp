// SPDX-License-Identifier: BSD-3-Clause
// The structured solve of the nested step system (docs/asynchronous-integrator.md, "The
// structured solve", Eqs. N9-N12): level by level, one factor per level, not per step.
// Private to the library.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SparseCore>
#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <memory>
#include <string>
#include <vector>

namespace asyncfem::detail {

/// Solves HierarchySystem's step system when the step counts form a chain 1 = c_0 | c_1 |
/// ... | c_K (every count divides the next). The unknowns are laid out as a tree of time
/// blocks (Eq. N9): the block of level l and step j holds, in order, its c_{l+1}/c_l child
/// blocks of level l+1 (the faster steps inside step j) and then its own unknowns, the
/// v and w of the level-l DOFs at step j. In that order a block couples only to its
/// previous sibling (the same matrix P_l for every step: the system is invariant under
/// a shift by one step of any level) and to its ancestors' own unknowns, which its parent
/// eliminates by a Schur complement on the interface (Eq. N10). So one factor per level
/// serves all its steps, and one large step costs about what the two-level forward
/// substitution of Eq. A13 costs per level.
class StructuredHierarchySolve {
 public:
  using SparseMatrix = Eigen::SparseMatrix<double>;

  /// Whether the distinct counts (any order, 1 implied) form a chain.
  static bool applies(const std::vector<int>& counts);
  /// dofCount[d]: steps of free DOF d; its unknowns v_{d,j} and w_{d,j} (j = 1..N_d) are
  /// rows offset[d] + j - 1 and velocityUnknowns + offset[d] + j - 1 of the system.
  StructuredHierarchySolve(const std::vector<int>& dofCount, const std::vector<int>& offset, int velocityUnknowns);
  ~StructuredHierarchySolve();

  /// Cuts the per-level blocks from the step system, computes the Schur complements from
  /// the finest level up and factors them (symbolic analyses kept while patterns stay).
  /// Throws asyncfem::NumericalError when a level's Schur complement is singular.
  void factor(const SparseMatrix& system, IntegratorStats& stats);
  /// solution = system^{-1} rhs (original indexing). With allUnknowns false only the
  /// end-of-step unknowns (each DOF's last step) are exact; the others are left as the
  /// intermediate values the solve needed (Eq. N12).
  void solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution, bool allUnknowns);

  /// Largest error of the end-of-step unknowns, relative to the largest unknown, when
  /// solving system x = system * x_test for a fixed x_test: round-off when the system has
  /// the structure the solve assumes (Eq. N9), order one when it does not.
  double checkEndState(const SparseMatrix& system);
  /// Flops of one solve (end-of-step unknowns only), from the blocks' sizes: every sparse
  /// product and dense recovery included.
  double solveFlops() const { return solveFlops_; }
  /// Of those, the substitutions with the levels' factors alone: what the other
  /// integrators' IntegratorStats::solveFlops count (the solver libraries' figures).
  double substitutionFlops() const { return substitutionFlops_; }
  /// Entries kept: factor non-zeros plus the dense Z rows stored for recovery.
  long long storedEntries() const;
  /// One line per level: its DOFs, interface, solver and recovery.
  std::string describe() const;

 private:
  struct Level;
  void layOut(int level, long long block, int& position);
  void chooseNeeded();
  void factorLevel(int level, IntegratorStats& stats);
  void computeZ(int level, const std::vector<int>& rows, bool keepZ, IntegratorStats& stats);
  void factorSchur(int level, const std::vector<int>& rows, IntegratorStats& stats);
  /// The block of `level` whose right-hand sides (columns) are x, solved in place.
  void solveBlock(int level, Eigen::Ref<Eigen::MatrixXd> x, bool all);
  /// The children of a block of `level` with its own unknowns zero (forward in time).
  void forwardChildren(int level, Eigen::Ref<Eigen::MatrixXd> x, bool all);
  double blockFlops(int level) const;

  std::vector<int> counts_;               // c_0 = 1 < c_1 < ... (the chain)
  std::vector<std::vector<int>> dofsOf_;  // free DOFs of each level
  std::vector<int> dofLevel_, offset_;    // per free DOF
  int velocityUnknowns_ = 0;
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> order_;  // unknown -> tree position
  std::vector<std::unique_ptr<Level>> levels_;
  double solveFlops_ = 0.0, substitutionFlops_ = 0.0;
  bool factored_ = false;
  Eigen::MatrixXd work_;
};

}  // namespace asyncfem::detail
