// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/core/vertexJacobian.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <unordered_map>

#include "detail/freeSystem.hpp"

namespace asyncfem::detail {

/// Solves (A_0 + sum_k E_k B_k E_k^T + sum_p s_p g_p g_p^T) x = b, A_0 a matrix kept
/// factored (a linear model's M + h D + h^2 K), B_k the 3 x 3 contact blocks of a few
/// vertices (E_k: the vertex's free DOFs) and g_p the couplings' vectors (a surface pair's
/// w_i N at its up to four vertices, off-diagonal blocks included), without factoring the
/// sum: with U the columns sqrt(lambda) q of every block's eigenpairs (lambda > 0; a
/// plane's k n n^T gives one) and sqrt(s_p) g_p of every coupling, the Sherman-Morrison-
/// Woodbury identity
///
///     (A_0 + U U^T)^{-1} b = y - Y (I + U^T Y)^{-1} U^T y,   y = A_0^{-1} b, Y = A_0^{-1} U
///
/// costs one substitution with A_0's factor, Y from columns A_0^{-1} E_v cached per vertex
/// (a coupling's column is the sum of its vertices' cached columns times w_i N)
/// (three substitutions the first time a vertex is in contact, none after while A_0
/// stands) and a dense Cholesky factorization of the r x r matrix I + U^T Y (r the rank).
/// Deterministic: the cached columns do not depend on when they were computed, so a
/// resumed run repeats the solves bit for bit.
class LowRankContactSolver {
 public:
  /// Whether the update is cheaper than a factorization of the sum for these blocks (by
  /// flop counts: the dense work against factorFlops), and the cache would stay within
  /// its memory bound.
  bool pays(const FreeSystem& free, const FreeDofs& dofs, const VertexJacobian& contact) const;
  /// x = (A_0 + contact blocks, weighted as FreeSystem::addVertexBlocks does)^{-1} b;
  /// free's factor must be A_0's.
  void solve(FreeSystem& free, const FreeDofs& dofs, const VertexJacobian& contact, double stiffnessWeight,
             double dampingWeight, const Eigen::VectorXd& rhs, Eigen::VectorXd& x, IntegratorStats& stats);
  /// A_0 changed (a new timestep): the cached columns are dropped.
  void clear() { columns_.clear(); }
  std::size_t cachedVertices() const { return columns_.size(); }

 private:
  /// The update's columns U (u_, entryVertex_, start_) for this contact Jacobian.
  void buildColumns(const FreeDofs& dofs, const VertexJacobian& contact, double stiffnessWeight, double dampingWeight);
  /// A_0^{-1} E_v on the free DOFs (n x 3; zero columns for fixed DOFs), computed once.
  const Eigen::MatrixXd& columnsOf(int vertex, FreeSystem& free, const FreeDofs& dofs, IntegratorStats& stats);

  std::unordered_map<int, Eigen::MatrixXd> columns_;
  // Scratch.
  Eigen::MatrixXd u_;             // 3 x entries: each entry's block coordinates
  std::vector<int> entryVertex_;  // per entry: its vertex
  std::vector<int> start_;        // column j's entries are [start_[j], start_[j + 1])
  Eigen::MatrixXd y_, small_;
  Eigen::VectorXd base_, projected_;
};

}  // namespace asyncfem::detail
