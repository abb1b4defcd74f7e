// SPDX-License-Identifier: BSD-3-Clause
// Pieces both multirate integrators (AsyncBackwardEuler, UncoupledMultirate) use: block
// extraction, counted factorizations, the force evaluation of a large step, solve
// statistics and the state check. Private to the library.
#pragma once

#include <Eigen/SparseCore>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "detail/fastRegion.hpp"

namespace asyncfem::detail {

/// Entries of a full vector at the listed global DOFs.
inline Eigen::VectorXd gather(const Eigen::VectorXd& full, const std::vector<int>& dofs) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(dofs.size()));
  for (std::size_t k = 0; k < dofs.size(); ++k) out[static_cast<Eigen::Index>(k)] = full[dofs[k]];
  return out;
}

/// out = the entries of full at the listed global DOFs, without allocating when out
/// already has that size (per-step buffers).
inline void gatherInto(const Eigen::VectorXd& full, const std::vector<int>& dofs, Eigen::VectorXd& out) {
  out.resize(static_cast<Eigen::Index>(dofs.size()));
  for (std::size_t k = 0; k < dofs.size(); ++k) out[static_cast<Eigen::Index>(k)] = full[dofs[k]];
}

/// sub = full(rows, cols) through the extractor: cut (pattern and values) the first time,
/// values only once `alreadyCut`.
inline void updateBlock(const SubmatrixExtractor& extractor, const Eigen::SparseMatrix<double>& full,
                        Eigen::SparseMatrix<double>& sub, bool alreadyCut) {
  if (alreadyCut) {
    extractor.update(full, sub);
  } else {
    sub = extractor.extract(full);
  }
}

/// Numeric factorization of matrix, with the symbolic analysis done once (`analyzed`),
/// counted in stats (the caller times it).
inline void factorizeCounted(SparseSolver& solver, const Eigen::SparseMatrix<double>& matrix, bool& analyzed,
                             IntegratorStats& stats) {
  if (!analyzed) {
    solver.analyzePattern(matrix);
    analyzed = true;
  }
  solver.factorize(matrix);
  ++stats.factorizations;
  stats.factorFlops += solver.stats().factorFlops;
}

/// f_int(u_0) every large step; K(u_0) too for nonlinear models, and for linear ones only
/// while `built` is false (it is then constant). Timed into stats.forceSeconds.
inline void evaluateForces(const DynamicSystem& system, bool linear, bool built, const Eigen::VectorXd& u0,
                           Eigen::VectorXd& internalForce, Eigen::SparseMatrix<double>& stiffness,
                           IntegratorStats& stats) {
  Stopwatch forces;
  forces.start();
  if (linear) {
    if (!built) system.forceModel->tangentStiffness(u0, stiffness);
    system.forceModel->internalForces(u0, internalForce);
  } else {
    system.forceModel->forcesAndTangent(u0, internalForce, stiffness);
  }
  stats.forceSeconds += forces.stop();
}

/// Adds a solver's back-substitution count and flops to stats.
inline void addSolveCounts(const SparseSolver& solver, IntegratorStats& stats) {
  stats.solvedRightHandSides += solver.stats().solvedRightHandSides;
  stats.solveFlops += static_cast<double>(solver.stats().solvedRightHandSides) * solver.stats().solveFlopsPerRhs;
}

/// The set-up the two comparators share (UncoupledMultirate, Schroeder2011), on their Impl d:
/// M and d.stiffness cut to the free DOFs (d.freeMass, d.freeStiffness, d.Mff), each free
/// DOF's region (d.freeRegion, -1: L), the compound system's solver, and one d.regions entry
/// per fast region (its blocks on the region's layout, factored by regionSolver).
template <typename Impl>
void setUpCompoundBlocks(const DynamicSystem& system, const RegionPartition& partition, SolverKind regionSolver,
                         SolverKind compoundSolver, Impl& d) {
  const std::vector<int>& free = system.freeDofs.freeToFull();
  d.freeMass = SubmatrixExtractor(system.mass, free, free);
  d.freeStiffness = SubmatrixExtractor(d.stiffness, free, free);
  d.Mff = d.freeMass.extract(system.mass);
  d.freeRegion.resize(free.size());
  for (std::size_t k = 0; k < free.size(); ++k)
    d.freeRegion[k] = partition.vertexRegion()[static_cast<std::size_t>(free[k] / 3)];
  d.compoundSolver = makeSparseSolver(compoundSolver);
  d.regions.reserve(static_cast<std::size_t>(partition.numRegions()));
  for (int i = 0; i < partition.numRegions(); ++i) {
    const RegionLayout layout{&partition.regionDofs(i), &partition.interfaceDofs(i), partition.ratio(i)};
    d.regions.emplace_back(system.mass, d.stiffness, layout, regionSolver);
  }
}

}  // namespace asyncfem::detail
