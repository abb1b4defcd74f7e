// SPDX-License-Identifier: BSD-3-Clause
// Uncoupled (compound-step) multirate backward Euler; the equations are in the header.
#include <Eigen/SparseCore>
#include <asyncfem/asyncIntegrator/uncoupledMultirate.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <cmath>
#include <string>

#include "detail/fastRegion.hpp"
#include "detail/multirateSupport.hpp"

namespace asyncfem {

namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;

using detail::gather;
using detail::updateBlock;

/// The blocks one fast region needs for its lone substeps r >= 2 (I: its interface DOFs):
/// M^{SS}, M^{SI}, K^{SS}, K^{SI} and A^S of the asynchronous integrator's FastRegion.
using RegionBlocks = detail::FastRegion;

}  // namespace

struct UncoupledMultirate::Impl {
  bool linear = true;
  bool built = false;
  SparseMatrix stiffness;  // K(u_0), full
  Eigen::VectorXd internalForce;
  SubmatrixExtractor freeMass, freeStiffness;
  SparseMatrix Mff, Kff;
  bool cutFree = false;
  std::vector<int> freeRegion;  // region of every free DOF (-1: L)
  SparseMatrix compound;
  std::unique_ptr<SparseSolver> compoundSolver;
  bool compoundAnalyzed = false;
  std::vector<RegionBlocks> regions;
};

UncoupledMultirate::UncoupledMultirate(const TetMesh& mesh, DynamicSystem system, double largeTimestep,
                                       std::vector<AsyncRegion> regions, UncoupledMultirateOptions options)
    : UncoupledMultirate(withMesh("multirate-uncoupled", mesh, std::move(system)), largeTimestep, std::move(regions),
                         options) {}

UncoupledMultirate::UncoupledMultirate(DynamicSystem system, double largeTimestep, std::vector<AsyncRegion> regions,
                                       UncoupledMultirateOptions options)
    : PartitionedIntegrator("multirate-uncoupled", std::move(system), largeTimestep, std::move(regions), false),
      options_(options),
      impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.linear = system_.forceModel->isLinear();
  d.stiffness = system_.forceModel->createStiffnessMatrix();
  d.stiffness.makeCompressed();
  detail::setUpCompoundBlocks(system_, partition_, options_.regionSolver, options_.compoundSolver, d);
  if (!system_.damped()) stats_.skipped.push_back("damping terms (alpha = beta = 0)");
  if (d.linear) stats_.skipped.push_back("per-step refactorization (linear forces: factored once)");
}

UncoupledMultirate::~UncoupledMultirate() = default;

void UncoupledMultirate::setTimestep(double timestep) {
  Integrator::setTimestep(timestep);
  if (impl_) impl_->built = false;
}

void UncoupledMultirate::rebuild() {
  Impl& d = *impl_;
  const double hL = timestep();
  const double alpha = system_.rayleighMass, beta = system_.rayleighStiffness;
  Stopwatch assembly, factor;
  assembly.start();
  updateBlock(d.freeStiffness, d.stiffness, d.Kff, d.cutFree);
  d.cutFree = true;
  // Row of a fast region i: c (M + hS D + hS^2 K) with c = 1/m_i on L columns (the
  // interpolated v^L_1); row of L: M + hL D + hL^2 K (backward Euler at hL).
  auto rowStep = [&](int region) { return region < 0 ? hL : hL / partition_.ratio(region); };
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(d.Mff.nonZeros() + d.Kff.nonZeros()));
  auto add = [&](const SparseMatrix& matrix, bool isMass) {
    for (int c = 0; c < matrix.outerSize(); ++c) {
      const int columnRegion = d.freeRegion[static_cast<std::size_t>(c)];
      for (SparseMatrix::InnerIterator it(matrix, c); it; ++it) {
        const int rowRegion = d.freeRegion[static_cast<std::size_t>(it.row())];
        const double h = rowStep(rowRegion);
        const double scale = (rowRegion >= 0 && columnRegion < 0) ? 1.0 / partition_.ratio(rowRegion) : 1.0;
        const double weight = isMass ? 1.0 + h * alpha : h * h + h * beta;
        triplets.emplace_back(static_cast<int>(it.row()), c, scale * weight * it.value());
      }
    }
  };
  add(d.Mff, true);
  add(d.Kff, false);
  d.compound.resize(d.Mff.rows(), d.Mff.cols());
  d.compound.setFromTriplets(triplets.begin(), triplets.end());
  d.compound.makeCompressed();
  for (RegionBlocks& rb : d.regions) {
    rb.smallStep = hL / rb.ratio;
    const double hS = rb.smallStep;
    rb.updateStiffnessBlocks(d.stiffness);
    rb.systemMatrix = (1.0 + hS * alpha) * rb.Mss + (hS * hS + hS * beta) * rb.Kss;
    rb.systemMatrix.makeCompressed();
  }
  stats_.assemblySeconds += assembly.stop();

  factor.start();
  detail::factorizeCounted(*d.compoundSolver, d.compound, d.compoundAnalyzed, stats_);
  for (RegionBlocks& rb : d.regions) {
    if (rb.ratio == 1) continue;  // no lone substep: A^S is never solved
    detail::factorizeCounted(*rb.solver, rb.systemMatrix, rb.analyzed, stats_);
  }
  stats_.factorizationSeconds += factor.stop();
}

void UncoupledMultirate::step() {
  Impl& d = *impl_;
  // Step times from the step index (t0 = k hL, t1 = (k + 1) hL); the last substep of a
  // region (r = m) is at exactly t1.
  const double t0 = time();
  const double t1 = stepEndTime();
  detail::evaluateForces(system_, d.linear, d.built, displacement_, d.internalForce, d.stiffness, stats_);
  Stopwatch solve;
  if (!d.linear || !d.built) {
    rebuild();
    d.built = true;
  }
  solve.start();
  const Eigen::VectorXd change = d.compoundSolver->solve(compoundRightHandSide(t0, t1));  // X_i on S, Y on L
  Eigen::VectorXd newU = displacement_, newV = velocity_;
  const std::vector<int>& free = system_.freeDofs.freeToFull();
  for (std::size_t k = 0; k < free.size(); ++k) {
    if (d.freeRegion[k] >= 0) continue;
    const int dof = free[k];
    newV[dof] = velocity_[dof] + change[static_cast<Eigen::Index>(k)];
    newU[dof] = displacement_[dof] + timestep() * newV[dof];
  }
  for (int i = 0; i < partition_.numRegions(); ++i) loneSubsteps(i, t0, t1, change, newU, newV);
  stats_.solveSeconds += solve.stop();
  commitStep(newU, newV);
  stats_.solvedRightHandSides = 0;
  stats_.solveFlops = 0.0;
  detail::addSolveCounts(*d.compoundSolver, stats_);
  for (const RegionBlocks& rb : d.regions) detail::addSolveCounts(*rb.solver, stats_);
}

// b = h (f_ext(t_0 + h) - f_int(u_0) - D v_0 - h K v_0) with h = hS_i on the rows of S_i and
// hL on the rows of L.
Eigen::VectorXd UncoupledMultirate::compoundRightHandSide(double t0, double t1) {
  Impl& d = *impl_;
  const Eigen::VectorXd& v0 = velocity_;
  const double alpha = system_.rayleighMass, beta = system_.rayleighStiffness;
  const Eigen::VectorXd stiffVelocity = d.stiffness * v0;
  Eigen::VectorXd stateForce = d.internalForce;
  if (system_.damped()) stateForce += alpha * (system_.mass * v0) + beta * stiffVelocity;
  const int numRegions = partition_.numRegions();
  std::vector<Eigen::VectorXd> externalAtFirstSubstep(static_cast<std::size_t>(numRegions));
  for (int i = 0; i < numRegions; ++i) {
    const RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
    evaluateExternalForce(rb.ratio == 1 ? t1 : t0 + rb.smallStep, externalAtFirstSubstep[static_cast<std::size_t>(i)]);
  }
  Eigen::VectorXd externalForce;
  evaluateExternalForce(t1, externalForce);
  const std::vector<int>& free = system_.freeDofs.freeToFull();
  Eigen::VectorXd rhs(static_cast<Eigen::Index>(free.size()));
  for (std::size_t k = 0; k < free.size(); ++k) {
    const int dof = free[k];
    const int region = d.freeRegion[k];
    const double h = region < 0 ? timestep() : d.regions[static_cast<std::size_t>(region)].smallStep;
    const double fext = region < 0 ? externalForce[dof] : externalAtFirstSubstep[static_cast<std::size_t>(region)][dof];
    rhs[static_cast<Eigen::Index>(k)] = h * (fext - stateForce[dof] - h * stiffVelocity[dof]);
  }
  return rhs;
}

// Region i's substeps r = 2..m alone, L frozen at its interpolated state (step 3 of the
// class comment), from the compound step's change; the end state into newU, newV.
void UncoupledMultirate::loneSubsteps(int i, double t0, double t1, const Eigen::VectorXd& change, Eigen::VectorXd& newU,
                                      Eigen::VectorXd& newV) {
  Impl& d = *impl_;
  const Eigen::VectorXd& u0 = displacement_;
  const Eigen::VectorXd& v0 = velocity_;
  const double alpha = system_.rayleighMass, beta = system_.rayleighStiffness;
  RegionBlocks& rb = d.regions[static_cast<std::size_t>(i)];
  const double hS = rb.smallStep;
  const int m = rb.ratio;
  const std::vector<int>& s = partition_.regionDofs(i);
  const std::vector<int>& iface = partition_.interfaceDofs(i);
  const std::vector<int>& fullToFree = system_.freeDofs.fullToFree();
  const Eigen::VectorXd uS0 = gather(u0, s);
  Eigen::VectorXd vS = gather(v0, s);
  for (std::size_t k = 0; k < s.size(); ++k)
    vS[static_cast<Eigen::Index>(k)] += change[fullToFree[static_cast<std::size_t>(s[k])]];
  Eigen::VectorXd uS = uS0 + hS * vS;
  if (m > 1) {
    // L frozen: its interface velocity change Y_I, interpolated over the substeps.
    const Eigen::VectorXd vL0 = gather(v0, iface);
    Eigen::VectorXd changeL(static_cast<Eigen::Index>(iface.size()));
    for (std::size_t k = 0; k < iface.size(); ++k)
      changeL[static_cast<Eigen::Index>(k)] = change[fullToFree[static_cast<std::size_t>(iface[k])]];
    const Eigen::VectorXd fintS = gather(d.internalForce, s);
    Eigen::VectorXd rhsS, dS, vLr, externalForce;
    for (int r = 2; r <= m; ++r) {
      evaluateExternalForce(r == m ? t1 : t0 + (r * hS), externalForce);
      vLr = vL0 + (double(r) / m) * changeL;
      const Eigen::VectorXd uLdiff = (r * hS) * vLr;
      const Eigen::VectorXd uSdiff = uS + hS * vS - uS0;
      rhsS = hS * (gather(externalForce, s) - fintS);
      rhsS -= rb.Msi * ((1.0 / m) * changeL);
      rhsS -= hS * (rb.Kss * uSdiff + rb.Ksi * uLdiff);
      if (system_.damped()) {
        rhsS -= (hS * alpha) * (rb.Mss * vS + rb.Msi * vLr);
        rhsS -= (hS * beta) * (rb.Kss * vS + rb.Ksi * vLr);
      }
      dS = rb.solver->solve(rhsS);
      vS += dS;
      uS += hS * vS;
    }
  }
  for (std::size_t k = 0; k < s.size(); ++k) {
    newV[s[k]] = vS[static_cast<Eigen::Index>(k)];
    newU[s[k]] = uS[static_cast<Eigen::Index>(k)];
  }
}

RunReport UncoupledMultirate::report() const {
  RunReport report;
  report.factorNonZeros = factorNonZeros();
  return report;
}

long long UncoupledMultirate::factorNonZeros() const {
  long long total = impl_->compoundSolver->stats().factorNonZeros;
  for (const RegionBlocks& rb : impl_->regions) total += rb.solver->stats().factorNonZeros;
  return total;
}

}  // namespace asyncfem
