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

/// Settings of Schroeder2011.
struct Schroeder2011Options {
  /// Factors the coupled end-of-step system (S6) (unsymmetric: needs an LU kind).
  SolverKind compoundSolver = SolverKind::umfpack;
  /// Factors each substep matrix M^{SS} + hS D^{SS} of (S3) (SPD).
  SolverKind regionSolver = SolverKind::cholmod;
  /// Weight rho in [0, 1] of the force distributing projection (S5): 1 spreads the
  /// impulse the outer layer exerts on the interior during the substeps as a rigid-body
  /// impulse of the whole interior (same net force and torque); 0 leaves it on the
  /// interface DOFs where it acts.
  double rigidity = 1.0;
  /// Run even when a substep exceeds the outer layer's explicit stability limit (S7).
  bool force = false;
};

/// The force distributing projection of Schroeder et al. 2011 (Eq. (S5) of
/// docs/asynchronous-integrator.md): the mass-weighted projection of an impulse field on a
/// set of DOFs onto the impulses of rigid-body motions of those DOFs,
///
///     P J = W Phi (Phi^T W Phi)^+ Phi^T J,
///
/// with W the diagonal of lumped masses (kg) and Phi (|dofs| x 6) the three translations
/// and the three infinitesimal rotations about the set's centroid at the given positions.
/// P J has the net force and the net torque (about any point) of J, P is the identity on
/// impulses m_p (a + alpha x r_p) of a rigid acceleration, and it maps an impulse with
/// zero net force and torque (e.g. the elastic force of a rigid displacement) to zero.
class RigidImpulseProjection {
 public:
  RigidImpulseProjection() = default;
  /// positions: current positions (3n, m) of every vertex; lumpedMass: mass per DOF (3n,
  /// kg, positive on dofs); dofs: the global DOFs of the set (ascending). Translations or
  /// rotations the set cannot carry (a set on a line, a single vertex) are dropped (the
  /// pseudo-inverse).
  RigidImpulseProjection(const Eigen::VectorXd& positions, const Eigen::VectorXd& lumpedMass, std::vector<int> dofs);

  /// out = (1 - rigidity) J + rigidity P J for an impulse J given on all 3n DOFs (only its
  /// entries on dofs are read; out is zero elsewhere).
  Eigen::VectorXd apply(const Eigen::VectorXd& impulse, double rigidity = 1.0) const;
  const std::vector<int>& dofs() const { return dofs_; }

 private:
  std::vector<int> dofs_;
  Eigen::MatrixXd weightedModes_;   // W Phi, |dofs| x 6
  Eigen::MatrixXd modes_;           // Phi, |dofs| x 6
  Eigen::MatrixXd inverseInertia_;  // (Phi^T W Phi)^+, 6 x 6
};

/// The asynchronous scheme of Schroeder, Kwatra, Zheng & Fedkiw, "Asynchronous evolution
/// for fully-implicit and semi-implicit time integration" (Computer Graphics Forum 30(7),
/// 2011), the second comparator of Zhao, Li & Barbic 2016 (their Figure 9), on the regions
/// of the asynchronous integrator: the fast regions S_i (ratio m_i, hS = hL / m_i) are the
/// semi-implicit outer layer, L the fully implicit interior. The equations (S1)-(S7) are
/// in docs/asynchronous-integrator.md, section "Schroeder et al. 2011"; in brief, one large
/// step from (u_0, v_0) with f_int(u_0) and K = K(u_0) (the same linearization as the other
/// multirate integrators):
///
/// 1. Substeps r = 1..m-1 of every S_i, explicit in the elastic force and implicit in the
///    damping (S3), with the interior left behind: L moves with its frame-start velocity.
///    The impulse the outer layer's elements exert on the interface DOFs is accumulated.
/// 2. That impulse is filtered by the force distributing projection (S5) onto the rigid
///    motions of the interior.
/// 3. One implicit solve (S6) couples the last substep of every S_i with L's whole step
///    hL (L's own elements over hL, the interface elements over the last substep hS, the
///    filtered impulse added to L's rows). The matrix is unsymmetric (LU).
///
/// Every m_i = 1 (and no region at all) is backward Euler at hL. Linear momentum is
/// conserved when alpha = 0, nothing is fixed and no external force acts (S4). The
/// substeps are stable for hS_i <= (S7); a larger substep throws TimestepError naming the
/// region and its largest stable substep unless options.force. Throws the ValidationErrors
/// of RegionPartition, and NumericalError for a non-finite state.
class Schroeder2011 final : public PartitionedIntegrator {
 public:
  /// system.mesh must be set (Problem::dynamicSystem() sets it).
  Schroeder2011(DynamicSystem system, double largeTimestep, std::vector<AsyncRegion> regions,
                Schroeder2011Options options = {});
  /// The same for a system assembled by hand without its mesh: mesh is copied into it.
  Schroeder2011(const TetMesh& mesh, DynamicSystem system, double largeTimestep, std::vector<AsyncRegion> regions,
                Schroeder2011Options options = {});
  ~Schroeder2011() override;

  std::string name() const override { return "schroeder2011"; }
  void step() override;
  /// Checks the substeps against (S7) (TimestepError unless options().force) and refactors
  /// lazily.
  void setTimestep(double timestep) override;
  /// The largest large step every region's substeps are stable at: min_i m_i hS*_i (S7).
  double stableTimestepEstimate() const override;

  /// hS*_i (S7) of region i, seconds: the largest stable substep of its outer layer, from
  /// the rest tangent (linear models) or the tangent at the state the integrator was built
  /// with (nonlinear ones).
  double largestStableSubstep(int region) const;
  /// omega_max of region i's substep system (K^{SS}, M^{SS}), rad/s (an upper estimate).
  double outerLayerMaxFrequency(int region) const;

  const Schroeder2011Options& options() const { return options_; }
  /// Sum over the factorizations this integrator owns of the factor non-zeros.
  long long factorNonZeros() const;
  /// factorNonZeros().
  RunReport report() const override;

 private:
  void collectInterfaceElements();
  void checkInterfaceStiffness() const;
  void appendSteppedBlocks(std::vector<Eigen::Triplet<double>>& triplets) const;
  struct Impl;
  void rebuild();
  void checkSubsteps(double largeTimestep) const;
  /// An interface element's tangent at u: the model's element tangent, or the mesh's
  /// linear FEM element stiffness for a linear model without one.
  void interfaceTangent(const Eigen::VectorXd& u, int element, Eigen::MatrixXd& tangent) const;
  void substeps(int region, double t0, Eigen::VectorXd& boundaryImpulse);
  Eigen::VectorXd coupledRightHandSide(double t1, const Eigen::VectorXd& boundaryImpulse);
  Schroeder2011Options options_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace asyncfem
