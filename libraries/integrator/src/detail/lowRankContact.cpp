// SPDX-License-Identifier: BSD-3-Clause
#include "detail/lowRankContact.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/contactBlock.hpp>
#include <cmath>
#include <unordered_set>

namespace asyncfem::detail {

namespace {

// The cache holds at most this many doubles (256 MiB): past it a contact solve factors.
constexpr double kMaxCachedDoubles = 32.0 * 1024 * 1024;

}  // namespace

bool LowRankContactSolver::pays(const FreeSystem& free, const FreeDofs& dofs, const VertexJacobian& contact) const {
  const double n = dofs.numFree();
  // At most three columns per block, one per coupling.
  const double rank =
      (3.0 * static_cast<double>(contact.vertices.size())) + static_cast<double>(contact.couplings.size());
  int uncached = 0;
  if (contact.couplings.empty()) {
    for (const int v : contact.vertices) uncached += columns_.count(v) == 0 ? 1 : 0;
  } else {
    std::unordered_set<int> seen;
    const auto count = [&](int v) {
      if (v >= 0 && columns_.count(v) == 0 && seen.insert(v).second) ++uncached;
    };
    for (const int v : contact.vertices) count(v);
    for (const VertexCoupling& coupling : contact.couplings)
      for (const int v : coupling.vertices) count(v);
  }
  const double cached = static_cast<double>(columns_.size() + static_cast<std::size_t>(uncached));
  if (cached * 3.0 * n > kMaxCachedDoubles) return false;
  const SolverStats& solver = free.solver().stats();
  // Forming Y (n x r from n x 3 per block), U^T Y, applying Y, the r x r Cholesky and the
  // solve itself. A vertex's first contact adds three substitutions (its cached columns),
  // paid once for all the solves it takes part in: not counted here.
  const double dense = (6.0 * n * rank) + (2.0 * n * rank) + (rank * rank * rank / 3.0);
  const double substitutions = solver.solveFlopsPerRhs;
  return dense + substitutions < solver.factorFlops;
}

const Eigen::MatrixXd& LowRankContactSolver::columnsOf(int vertex, FreeSystem& free, const FreeDofs& dofs,
                                                       IntegratorStats& stats) {
  const auto found = columns_.find(vertex);
  if (found != columns_.end()) return found->second;
  const std::vector<int>& fullToFree = dofs.fullToFree();
  Eigen::MatrixXd unit = Eigen::MatrixXd::Zero(dofs.numFree(), 3);
  for (int c = 0; c < 3; ++c) {
    const int dof = fullToFree[static_cast<std::size_t>((3 * vertex) + c)];
    if (dof >= 0) unit(dof, c) = 1.0;
  }
  Eigen::MatrixXd solved;
  free.solve(unit, solved, stats);
  for (int c = 0; c < 3; ++c) {
    if (fullToFree[static_cast<std::size_t>((3 * vertex) + c)] < 0) solved.col(c).setZero();
  }
  return columns_.emplace(vertex, std::move(solved)).first->second;
}

// U: per block, sqrt(lambda) q for the positive eigenpairs of the block the step matrix
// would take (contactStepBlock, as addVertexBlocks adds it); per coupling, one column
// sqrt(h^2 k + h c) g, g = w_i N at its vertices. Column j has the entries
// [start_[j], start_[j + 1]): vertex entryVertex_[e], 3-vector u_.col(e).
void LowRankContactSolver::buildColumns(const FreeDofs& dofs, const VertexJacobian& contact, double stiffnessWeight,
                                        double dampingWeight) {
  u_.resize(3, static_cast<Eigen::Index>((3 * contact.vertices.size()) + (4 * contact.couplings.size())));
  entryVertex_.clear();
  start_.assign(1, 0);
  for (std::size_t k = 0; k < contact.vertices.size(); ++k) {
    const int vertex = contact.vertices[k];
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(
        contactStepBlock(dofs, contact, k, stiffnessWeight, dampingWeight));
    const double largest = eigen.eigenvalues().maxCoeff();
    for (int i = 0; i < 3; ++i) {
      const double lambda = eigen.eigenvalues()[i];
      if (!(lambda > 1e-14 * largest)) continue;
      u_.col(static_cast<Eigen::Index>(entryVertex_.size())) = std::sqrt(lambda) * eigen.eigenvectors().col(i);
      entryVertex_.push_back(vertex);
      start_.push_back(static_cast<int>(entryVertex_.size()));
    }
  }
  for (const VertexCoupling& coupling : contact.couplings) {
    const double weight = (stiffnessWeight * coupling.stiffness) + (dampingWeight * coupling.damping);
    if (!(weight > 0.0)) continue;
    const double root = std::sqrt(weight);
    for (std::size_t i = 0; i < 4; ++i) {
      if (coupling.vertices[i] < 0 || coupling.weights[i] == 0.0) continue;
      u_.col(static_cast<Eigen::Index>(entryVertex_.size())) = (root * coupling.weights[i]) * coupling.direction;
      entryVertex_.push_back(coupling.vertices[i]);
    }
    if (static_cast<int>(entryVertex_.size()) > start_.back()) start_.push_back(static_cast<int>(entryVertex_.size()));
  }
}

void LowRankContactSolver::solve(FreeSystem& free, const FreeDofs& dofs, const VertexJacobian& contact,
                                 double stiffnessWeight, double dampingWeight, const Eigen::VectorXd& rhs,
                                 Eigen::VectorXd& x, IntegratorStats& stats) {
  const std::vector<int>& fullToFree = dofs.fullToFree();
  buildColumns(dofs, contact, stiffnessWeight, dampingWeight);
  const auto rank = static_cast<Eigen::Index>(start_.size() - 1);
  free.solve(rhs, base_, stats);
  if (rank == 0) {
    x = base_;
    return;
  }
  // The vertices' cached columns first (substitutions, timed as solves by free), then the
  // dense work, timed here. Y = A_0^{-1} U, column j = sum over its entries e of C_v u_e.
  std::vector<const Eigen::MatrixXd*> columns(entryVertex_.size());
  for (std::size_t e = 0; e < entryVertex_.size(); ++e) columns[e] = &columnsOf(entryVertex_[e], free, dofs, stats);
  TimeInto timer(stats.solveSeconds);
  y_.resize(base_.size(), rank);
  for (Eigen::Index j = 0; j < rank; ++j) {
    const auto first = static_cast<std::size_t>(start_[static_cast<std::size_t>(j)]);
    const auto last = static_cast<std::size_t>(start_[static_cast<std::size_t>(j) + 1]);
    y_.col(j).noalias() = *columns[first] * u_.col(static_cast<Eigen::Index>(first));
    for (std::size_t e = first + 1; e < last; ++e)
      y_.col(j).noalias() += *columns[e] * u_.col(static_cast<Eigen::Index>(e));
  }
  // U^T z for a free vector z: u_e . z at vertex(e)'s free DOFs (fixed ones are zero in u).
  const auto projectOnto = [&](const auto& z, Eigen::Index i) {
    double sum = 0.0;
    for (int e = start_[static_cast<std::size_t>(i)]; e < start_[static_cast<std::size_t>(i) + 1]; ++e) {
      const int vertex = entryVertex_[static_cast<std::size_t>(e)];
      for (int c = 0; c < 3; ++c) {
        const int dof = fullToFree[static_cast<std::size_t>((3 * vertex) + c)];
        if (dof >= 0) sum += u_(c, e) * z[dof];
      }
    }
    return sum;
  };
  small_.setIdentity(rank, rank);
  for (Eigen::Index j = 0; j < rank; ++j) {
    const auto column = y_.col(j);
    for (Eigen::Index i = 0; i < rank; ++i) small_(i, j) += projectOnto(column, i);
  }
  // Symmetric in exact arithmetic; its lower triangle is what the factorization reads.
  const Eigen::LLT<Eigen::MatrixXd> factor(small_);
  if (factor.info() != Eigen::Success) {
    throw NumericalError("implicit contact: the low-rank update I + U^T A^{-1} U is not positive definite");
  }
  projected_.resize(rank);
  for (Eigen::Index i = 0; i < rank; ++i) projected_[i] = projectOnto(base_, i);
  x = base_;
  x.noalias() -= y_ * factor.solve(projected_);
}

}  // namespace asyncfem::detail
