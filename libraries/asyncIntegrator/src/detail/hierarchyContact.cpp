// SPDX-License-Identifier: BSD-3-Clause
// Implicit penalty contact in the hierarchy solve (docs/asynchronous-integrator.md, "Nested
// and touching regions", Eqs. N13-N14): Newton's method on the step equations of every
// DOF's steps with the external force at each step's own end state.
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <cmath>
#include <string>

#include "detail/hierarchySystem.hpp"
#include "detail/structuredHierarchySolve.hpp"

namespace asyncfem::detail {

void HierarchySystem::stateAt(long long t, const Eigen::VectorXd& x, const Eigen::VectorXd& u0,
                              const Eigen::VectorXd& v0, Eigen::VectorXd& u, Eigen::VectorXd& v) const {
  u = u0;
  v = v0;
  const double unit = largeStep_ / static_cast<double>(units_);
  for (int p = 0; p < static_cast<int>(free_.size()); ++p) {
    const long long sp = unitsPerStep(p);
    const long long jp = stepContaining(t, sp);
    if (jp == 0) continue;
    const int dof = free_[static_cast<std::size_t>(p)];
    const double before = jp >= 2 ? x[displacementRow(p, jp - 1)] : 0.0;
    const double elapsed = static_cast<double>(t - (jp - 1) * sp) * unit;
    u[dof] = u0[dof] + before + elapsed * x[velocityRow(p, jp)];
    v[dof] = x[velocityRow(p, jp)];
  }
}

void HierarchySystem::forcesAt(const Eigen::VectorXd& x, const Eigen::VectorXd& u0, const Eigen::VectorXd& v0,
                               const StateForce& force, std::map<long long, Eigen::VectorXd>& out) const {
  Eigen::VectorXd u, v;
  for (const long long t : stepEndUnits_) {
    stateAt(t, x, u0, v0, u, v);
    Eigen::VectorXd& f = out[t];
    f.setZero(u0.size());
    force.force(force.timeOf(t), u, v, f);
  }
}

double HierarchySystem::residualOf(const Eigen::VectorXd& x, const Eigen::VectorXd& rhs, double& norm,
                                   int& worstDof) const {
  const Eigen::VectorXd residual = matrix_ * x - rhs;
  norm = residual.norm();
  Eigen::Index row = 0;
  const double worst = residual.cwiseAbs().maxCoeff(&row);
  worstDof = -1;
  for (int d = 0; d < static_cast<int>(free_.size()) && worstDof < 0; ++d) {
    const int first = velocityRow(d, 1), last = velocityRow(d, dofCount_[static_cast<std::size_t>(d)]);
    if ((row >= first && row <= last) || (row >= first + velocityUnknowns_ && row <= last + velocityUnknowns_))
      worstDof = free_[static_cast<std::size_t>(d)];
  }
  return std::isfinite(norm) ? worst : std::numeric_limits<double>::quiet_NaN();
}

void HierarchySystem::solveWith(const std::vector<Eigen::Triplet<double>>& blocks, const Eigen::VectorXd& rhs,
                                Eigen::VectorXd& x, IntegratorStats& stats) {
  Stopwatch watch;
  watch.start();
  if (blocks.empty()) {
    if (structured_) {
      structured_->solve(rhs, x, true);
      stats.solveFlops += structured_->substitutionFlops();
    } else {
      x = order_.transpose() * lu_.solve(order_ * rowScale_.cwiseProduct(rhs));
      stats.solveFlops += 2.0 * static_cast<double>(factorNonZeros_);
    }
    ++stats.solvedRightHandSides;
    stats.solveSeconds += watch.stop();
    return;
  }
  SparseMatrix contact(matrix_.rows(), matrix_.cols());
  contact.setFromTriplets(blocks.begin(), blocks.end());
  if (rowScale_.size() != unknowns()) scalePositionRows();
  SparseMatrix ordered = order_ * SparseMatrix(rowScale_.asDiagonal() * (matrix_ + contact)) * order_.transpose();
  ordered.makeCompressed();
  // The blocks change the pattern from iterate to iterate: analysed each time, with the
  // pivoting of the kept LU (factorizeLU).
  contactLu_.setPivotThreshold(1e-3);
  contactLu_.analyzePattern(ordered);
  contactLu_.factorize(ordered);
  if (contactLu_.info() != Eigen::Success) {
    throw NumericalError("nested async regions: the step system with contact blocks is singular (" +
                         contactLu_.lastErrorMessage() + ")");
  }
  ++stats.factorizations;
  stats.factorizationSeconds += watch.stop();
  Stopwatch solve;
  solve.start();
  x = order_.transpose() * contactLu_.solve(order_ * rowScale_.cwiseProduct(rhs));
  ++stats.solvedRightHandSides;
  stats.solveFlops += 2.0 * static_cast<double>(contactLu_.nnzL() + contactLu_.nnzU());
  stats.solveSeconds += solve.stop();
}

// Eq. N13: the force on DOF d's step j taken at d's own state at t_{d,j}; Eq. N14: about an
// iterate x_i, f ~ f_i - K_c (w - w_i) - C_c (v - v_i) per vertex, so the rows of a vertex's
// step gain h_d K_c on its w and h_d C_c on its v, and the right-hand side h_d (K_c w_i + C_c v_i).
HierarchySystem::StateForceSolve HierarchySystem::solveWithStateForce(
    const Eigen::VectorXd& u0, const Eigen::VectorXd& v0, const Eigen::VectorXd& internalForce, const StateForce& force,
    double tolerance, int maxSolves, Eigen::VectorXd& u1, Eigen::VectorXd& v1, IntegratorStats& stats) {
  completeSolution();
  Eigen::VectorXd x = solution_;
  const double scale = std::max(rhs_.cwiseAbs().maxCoeff(), std::numeric_limits<double>::min());
  std::map<long long, Eigen::VectorXd> forces;
  Eigen::VectorXd rhs, trial, solved;
  StateForceSolve out;
  double norm = 0.0;
  const auto evaluate = [&](const Eigen::VectorXd& state, double& stateNorm, int& worstDof) {
    Stopwatch watch;
    watch.start();
    forcesAt(state, u0, v0, force, forces);
    stats.forceSeconds += watch.stop();
    loadRightHandSide(v0, internalForce, forces, rhs);
    return residualOf(state, rhs, stateNorm, worstDof) / scale;
  };
  out.residual = evaluate(x, norm, out.worstDof);
  std::vector<Eigen::Triplet<double>> blocks;
  VertexJacobian jacobian;
  Eigen::VectorXd u, v;
  while (std::isfinite(out.residual) && out.residual > tolerance && out.solves < maxSolves) {
    // The linearization at x: blocks and right-hand side (rhs holds f at x).
    blocks.clear();
    Eigen::VectorXd linear = rhs;
    for (const long long t : stepEndUnits_) {
      stateAt(t, x, u0, v0, u, v);
      force.jacobian(force.timeOf(t), u, v, jacobian);
      for (std::size_t k = 0; k < jacobian.vertices.size(); ++k) {
        const int vertex = jacobian.vertices[k];
        for (int a = 0; a < 3; ++a) {
          const int d = freeIndex_[static_cast<std::size_t>((3 * vertex) + a)];
          if (d < 0 || t % unitsPerStep(d) != 0) continue;  // not the end of one of d's steps
          const long long j = t / unitsPerStep(d);
          const double h = largeStep_ / dofCount_[static_cast<std::size_t>(d)];
          const int row = velocityRow(d, j);
          for (int b = 0; b < 3; ++b) {
            const int p = freeIndex_[static_cast<std::size_t>((3 * vertex) + b)];
            if (p < 0) continue;  // a vertex's DOFs share its step count: p's step j ends at t too
            const double k_ab = h * jacobian.stiffness[k](a, b), c_ab = h * jacobian.damping[k](a, b);
            blocks.emplace_back(row, displacementRow(p, j), k_ab);
            blocks.emplace_back(row, velocityRow(p, j), c_ab);
            linear[row] += (k_ab * x[displacementRow(p, j)]) + (c_ab * x[velocityRow(p, j)]);
          }
        }
      }
    }
    solveWith(blocks, linear, solved, stats);
    ++out.solves;
    if (!blocks.empty()) ++out.factorizations;
    // Halve the update while the residual's 2-norm would rise (at most 8 times).
    double theta = 1.0, trialNorm = 0.0;
    int worstDof = -1;
    for (int halvings = 0;; ++halvings, theta *= 0.5) {
      trial = x + theta * (solved - x);
      const double residual = evaluate(trial, trialNorm, worstDof);
      if ((std::isfinite(residual) && trialNorm < norm) || halvings == 8 || !std::isfinite(residual)) {
        out.residual = residual;
        break;
      }
    }
    x.swap(trial);
    norm = trialNorm;
    out.worstDof = worstDof;
  }
  out.converged = out.residual <= tolerance;
  solution_ = x;
  solutionComplete_ = true;
  endState(u0, v0, u1, v1);
  return out;
}

}  // namespace asyncfem::detail
