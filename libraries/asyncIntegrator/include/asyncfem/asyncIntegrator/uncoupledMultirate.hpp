// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/asyncIntegrator/partitionedIntegrator.hpp>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <memory>
#include <string>
#include <vector>

namespace asyncfem {

/// Settings of UncoupledMultirate.
struct UncoupledMultirateOptions {
  /// Factors the compound system (unsymmetric: needs an LU kind).
  SolverKind compoundSolver = SolverKind::umfpack;
  /// Factors each A^{S_i} = M^{SS} + hS D^{SS} + hS^2 K^{SS} (SPD).
  SolverKind regionSolver = SolverKind::cholmod;
};

/// The uncoupled multirate backward Euler scheme, after the compound-step multirate
/// methods of Constantinescu & Sandu (2010): the comparator the asynchronous integrator is
/// benchmarked against. Same regions as AsyncBackwardEuler (a RegionPartition: fast regions
/// S_i with ratios m_i, hS_i = hL / m_i, the rest L), same linearization (f_int(u_0) and
/// K = K(u_0) once per large step, D = alpha M + beta K) and the same external-force
/// sampling (S_i at t_0 + r hS_i, L at t_0 + hL). One large step from (u_0, v_0):
///
/// 1. Compound step. L's large step and the *first* substep of every S_i are solved
///    together, in one linear system on all free DOFs with unknowns X_i = v^{S_i}_1 - v^{S_i}_0
///    and Y = v^L_m - v^L_0:
///
///        A^{S_i} X_i + B_i Y = b^{S_i}_1                     (rows of S_i)
///        sum_i F_i X_i + A^L Y = b^L                         (rows of L)
///
///    with A^S = M^{SS} + hS D^{SS} + hS^2 K^{SS}, B = (M^{SL} + hS D^{SL} + hS^2 K^{SL}) / m
///    and b^S_1 exactly as row r = 1 of the asynchronous system (design note): S sees L's
///    velocity interpolated linearly, v^L_1 = v^L_0 + Y / m. L, however, sees S moving at
///    its first-substep velocity for the whole large step (u^S_m = u^S_0 + hL v^S_1), so
///    F = M^{LS} + hL D^{LS} + hL^2 K^{LS}: the L rows are plain backward Euler at hL.
///    The matrix is unsymmetric; it is factored by LU (compoundSolver).
/// 2. L is frozen: v^L_m = v^L_0 + Y, u^L_m = u^L_0 + hL v^L_m are final, and for the
///    remaining substeps L's state is the known interpolation v^L_r = v^L_0 + (r / m) Y,
///    u^L_r = u^L_0 + r hS v^L_r (as in the asynchronous method).
/// 3. Each S_i alone takes substeps r = 2..m_i of backward Euler at hS with L as a known
///    boundary: for the velocity change d_r = v^S_r - v^S_{r-1},
///
///        A^S d_r = hS f^S_ext(t_0 + r hS) - M^{SL} (v^L_r - v^L_{r-1})
///                  - hS [ f^S_int(u_0) + K^{SS} (u^S_{r-1} + hS v^S_{r-1} - u^S_0)
///                         + K^{SL} (u^L_r - u^L_0) + D^{SS} v^S_{r-1} + D^{SL} v^L_r ]
///
///    then v^S_r = v^S_{r-1} + d_r, u^S_r = u^S_{r-1} + hS v^S_r. (With r = 1 and Y unknown
///    this is exactly the S rows of step 1.)
///
/// What differs from the asynchronous method: L's equation never sees the substeps
/// r >= 2 of S (the coupling is one-way after the compound step), so the result differs
/// for m > 1. For every m_i = 1 the scheme is single-rate backward Euler at hL exactly (the
/// compound step is then the whole step). Cost per large step: one solve with the compound
/// factor (size of the free system) plus m_i - 1 solves with A^{S_i}; linear force models
/// factor both once (again after setTimestep), nonlinear ones refactor numerically per
/// large step. Throws the same ValidationErrors as RegionPartition, and NumericalError for a
/// non-finite state.
class UncoupledMultirate final : public PartitionedIntegrator {
 public:
  /// system.mesh must be set (Problem::dynamicSystem() sets it).
  UncoupledMultirate(DynamicSystem system, double largeTimestep, std::vector<AsyncRegion> regions,
                     UncoupledMultirateOptions options = {});
  /// The same for a system assembled by hand without its mesh: mesh is copied into it.
  UncoupledMultirate(const TetMesh& mesh, DynamicSystem system, double largeTimestep, std::vector<AsyncRegion> regions,
                     UncoupledMultirateOptions options = {});
  ~UncoupledMultirate() override;

  std::string name() const override { return "multirate-uncoupled"; }
  void step() override;
  void setTimestep(double timestep) override;

  const UncoupledMultirateOptions& options() const { return options_; }
  /// Sum over the factorizations this integrator owns of the factor non-zeros.
  long long factorNonZeros() const;
  /// factorNonZeros().
  RunReport report() const override;

 private:
  struct Impl;
  void rebuild();
  Eigen::VectorXd compoundRightHandSide(double t0, double t1);
  void loneSubsteps(int region, double t0, double t1, const Eigen::VectorXd& change, Eigen::VectorXd& newU,
                    Eigen::VectorXd& newV);
  UncoupledMultirateOptions options_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace asyncfem
