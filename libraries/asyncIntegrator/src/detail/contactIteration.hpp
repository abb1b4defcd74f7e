// SPDX-License-Identifier: BSD-3-Clause
// Implicit penalty contact in one asynchronous large step (docs/asynchronous-integrator.md,
// "Implicit contact", Eqs. C1-C5; C6 in the integrator). Private to the library.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/core/vertexJacobian.hpp>
#include <asyncfem/dynamics/dynamicSystem.hpp>
#include <utility>
#include <vector>

#include "detail/fastRegion.hpp"
#include "detail/rankedForces.hpp"
#include "detail/sparseBlocks.hpp"

namespace asyncfem::detail {

/// Time of substep r of a region with `ratio` substeps in the large step [t0, t1]; the last
/// one is exactly t1.
inline double substepTime(double t0, double t1, int r, int ratio, double smallStep) {
  return r == ratio ? t1 : t0 + (r * smallStep);
}

/// Whether a vertex with a free DOF lies within radius of an obstacle at `positions`
/// (displacements), the radius widened by a relative 1e-9 and 1e-12 (length) for the
/// round-off of the states it bounds: the search of Eqs. (C6) and (C7). near: scratch.
bool freeVertexNearObstacle(const DynamicSystem& system, const Eigen::VectorXd& positions, double radius,
                            std::vector<int>& near);

/// Contact blocks of L's vertices in the large system: hL^2 K_c + hL C_c per vertex
/// (contactStepBlock), at the L positions of its three DOFs (-1: fixed).
struct LargeContactBlocks {
  std::vector<std::array<int, 3>> positions;
  std::vector<Eigen::Matrix3d> values;

  bool empty() const { return positions.empty(); }
  bool operator==(const LargeContactBlocks& other) const;
};

/// The large step the contact iteration solves: its times, start state and partition
/// (referenced, alive for the step).
struct ContactStep {
  const DynamicSystem* system = nullptr;
  const RegionPartition* partition = nullptr;
  const Eigen::VectorXd* u0 = nullptr;
  const Eigen::VectorXd* v0 = nullptr;
  double t0 = 0.0, t1 = 0.0, hL = 0.0;
  /// Each region's vertices with free DOFs, ascending: at its substeps only they are
  /// evaluated (DynamicSystem::externalForceAt and externalForceJacobianAt where set).
  const std::vector<std::vector<int>>* regionVertices = nullptr;
  /// Whether start() may skip the predicted states where none can touch (Eq. C7; with
  /// AsyncOptions::Contact::certifyContactFree).
  bool screenPredicted = false;
  /// Set where the system has externalForceOfRank: the force terms are split by rank
  /// (RankedForces), and at a region's substep every vertex is where it is at that time (L
  /// on its constant-velocity path, the other regions on their backward Euler paths).
  RankedForces* ranked = nullptr;
};

/// The contact iteration of one large step: Newton's method on the step equations with the
/// external force at each fast substep's state and at L's end state (Eq. C3). The step's
/// linear system is the one of every other step plus the contact blocks of the vertices in
/// contact in the last iterate (Eq. C2: in Â^L for L's, at its end state; in A^S and G for
/// a region's, at the end state or else at the first substep where it touches, weighted by
/// the share of substeps where it touches). Each solve is mixed with the ones before
/// (Anderson, Eq. C5) or else backtracked on the residual's norm (Eq. C4).
class ContactIteration {
 public:
  /// Where each of the numDofs full DOFs sits in L or in its fast region (call at each
  /// set-up).
  void setPartition(const RegionPartition& partition, int numDofs);

  /// Starts a step from the predicted states (the increments zero): keeps the first
  /// solve's right-hand sides without their force terms g = h f_ext (externalL, full size,
  /// at the predicted end state for L; each region's `external` columns at its predicted
  /// substep states) and sets the contact blocks there (addBlocks; none, without visiting
  /// the states, where ContactStep::screenPredicted and predictedStatesClear(): returns
  /// whether it was so). Throws NumericalError
  /// naming the vertex where those forces are not finite.
  bool start(const ContactStep& step, const Eigen::VectorXd& rhsL, const Eigen::VectorXd& externalL,
             std::vector<FastRegion>& regions, Eigen::SparseMatrix<double>& largeSystem);
  /// One iteration after a solve (Y: L's velocity increments; each region's x: its
  /// substeps' increments): the state becomes the Anderson combination of the last solves
  /// where that lowers the residual's 2-norm, else it moves from the last accepted one
  /// toward the solve's, halved (up to kMaxHalvings times) while the norm would rise; Y and every
  /// x become that state. The contact blocks are then taken there (addBlocks: see
  /// changedRegions()) and the right-hand sides (rhsL and each region's rhs) set for the
  /// next solve. Returns the state's largest residual, relative to the step's scale (the
  /// largest entry of the first right-hand sides and force terms); NaN for a non-finite state.
  double update(std::vector<FastRegion>& regions, Eigen::VectorXd& Y, Eigen::SparseMatrix<double>& largeSystem,
                Eigen::VectorXd& rhsL);
  /// Restores the entries of largeSystem that L's blocks changed (the contact-free Â^L
  /// again, bit for bit). A region's blocks stay in its A^S (the next step's are often the
  /// same, and its factor with them).
  void removeBlocks(Eigen::SparseMatrix<double>& largeSystem);

  /// The regions whose A^S the last addBlocks changed (to refactor; their Z is stale).
  const std::vector<int>& changedRegions() const { return changedRegions_; }
  /// A factor of H^{LL*} was built from the large system as it is now.
  void noteFactored() { factored_ = inMatrix_; }
  /// Whether the last factor of H^{LL*} solves the current large system exactly.
  bool factorIsExact() const { return factored_ == inMatrix_; }
  bool blocksInMatrix() const { return !inMatrix_.empty(); }
  /// Whether this step's iteration stalled with the fast regions' blocks of surface pairs
  /// and went on without them (addBlocks).
  bool droppedPairBlocks() const { return droppedPairBlocks_; }
  /// The vertex with the largest residual after the last update (for error messages), -1 if none.
  int worstVertex() const { return worstVertex_; }

  static constexpr int kMaxHalvings = 8;
  /// Differences of solves the Anderson mixing of update() combines (Eq. C5): it keeps the
  /// last kMixingDepth + 1 solves.
  static constexpr int kMixingDepth = 8;

 private:
  /// Calls visit(time, region, r) at every state of the increments trialY_ and trialX_
  /// held in u_ and v_: first the end state (region -1, every region at its last substep),
  /// then each region's substeps r < m (the others at their end; with step_.ranked where
  /// they are at that substep's time: setOthersAt). u_, v_ end at the end state.
  template <class Visit>
  void visitStates(const std::vector<FastRegion>& regions, Visit&& visit);
  /// At region i's substep r, L and every other region where they are at its time: L at
  /// u_0 + r hS_i v^L, region j on its backward Euler path (prefix_: the running sums of
  /// its increments).
  void setOthersAt(const std::vector<FastRegion>& regions, std::size_t i, int r);
  /// G(z), the force terms h f_ext at the states of trialY_ and trialX_, into trialForceL_
  /// and trialForceS_.
  void forcesAt(const std::vector<FastRegion>& regions);
  /// The contact blocks at the states of trialY_ and trialX_, in place of the ones before;
  /// none where statesClear (no state visited can touch: predictedStatesClear).
  void addBlocks(Eigen::SparseMatrix<double>& largeSystem, std::vector<FastRegion>& regions, bool statesClear = false);
  /// addBlocks' blocks into the matrices (the regions' weighted by their touching share).
  void installBlocks(Eigen::SparseMatrix<double>& largeSystem, std::vector<FastRegion>& regions,
                     const std::vector<std::vector<std::array<int, 3>>>& positionsS,
                     std::vector<std::vector<Eigen::Matrix3d>>& blocksS,
                     std::vector<std::vector<Eigen::Matrix3d>>& stiffnessS);
  /// A ranked evaluation's pair couplings (in jacobian_) as per-vertex bounds: L's blocks
  /// into inMatrix_, the owner region's appended to jacobian_ (see addBlocks).
  void takePairBounds(int owner, int r, const std::vector<FastRegion>& regions);
  /// Whether no predicted state (the increments zero) comes within reach of an obstacle, so
  /// that every contact block there is zero (Eq. C7).
  bool predictedStatesClear();
  /// The largest residual of the trial state at theta along the update (worstVertex_:
  /// where), its 2-norm into merit.
  double trialResidual(const std::vector<FastRegion>& regions, double theta, double& merit);
  /// y += B x, B L's blocks in the large system.
  void addBlockProduct(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;
  /// Records the solve (its state Y, x and A_0 z - base there) and, with earlier solves
  /// kept, replaces it by their Anderson combination (Eq. C5). Returns whether it did.
  bool mix(Eigen::VectorXd& Y, std::vector<FastRegion>& regions);
  /// Drops the solves recorded for mixing (contactMixing.cpp).
  void forgetMixing();
  /// The state (and A_0 z - base) of the last solve recorded, back in Y, x and the solved operators.
  void unmix(Eigen::VectorXd& Y, std::vector<FastRegion>& regions);
  /// The residual at theta from the accepted state toward Y, x (trialY_, trialX_ set);
  /// NaN where that state is not finite (worstVertex_: its first vertex).
  double tryState(const std::vector<FastRegion>& regions, const Eigen::VectorXd& Y, double theta, double& merit);

  ContactStep step_;
  std::vector<int> largePosition_, regionPosition_, vertexRegion_, changedRegions_;
  LargeContactBlocks inMatrix_, factored_;
  KeptEntries saved_;  // entries of Â^L addBlocks changed, and their values before
  // The right-hand sides are base + g: g the force terms of the last solve (forceL_,
  // forceS_). The accepted state z (acceptedY_, acceptedX_), A_0 z - base there (operatorL_,
  // operatorS_; A_0 the step's operator without contact blocks) and its residual's norm
  // |A_0 z - base - G(z)|_2, which backtracking lowers (the max norm, reported, is not smooth).
  Eigen::VectorXd baseL_, forceL_, acceptedY_, operatorL_, solvedOperatorL_, blockProduct_;
  std::vector<Eigen::MatrixXd> baseS_, forceS_, acceptedX_, operatorS_, solvedOperatorS_;
  double meritNorm_ = 0.0, scale_ = 0.0;
  int worstVertex_ = -1;
  // A trial state and its force terms.
  Eigen::VectorXd trialY_, trialForceL_;
  std::vector<Eigen::MatrixXd> trialX_, trialForceS_;
  Eigen::VectorXd u_, v_, f_;            // full-size state and force
  std::vector<int> nearObstacles_;       // predictedStatesClear's proximity query
  Eigen::VectorXd running_, sums_;       // a region's sums of its substeps' increments
  Eigen::VectorXd endU_, endV_;          // the end state, while the substeps move every vertex
  std::vector<Eigen::MatrixXd> prefix_;  // per region, column c: the sum of its first c increments
  // The solves Anderson mixing combines: each one's state, A_0 z - base there and its step
  // from the state it started at, flattened (L's, then each region's column-major), oldest first.
  std::vector<Eigen::VectorXd> mixStates_, mixOperators_, mixSteps_;
  Eigen::VectorXd packed_;
  VertexJacobian jacobian_;
  // Per vertex in this addBlocks: 1 + the index of its block in its region's list (0:
  // none yet), and at how many of its region's substeps it touches.
  std::vector<int> blockSlot_, touches_;
  // Per vertex of L: 1 + the index of its ranked terms' block in inMatrix_ (0: none yet).
  std::vector<int> largeSlot_;
  VertexJacobian couplings_, bounded_;
  // forcesAt's derivatives at each state it visited (ranked terms, implicit contact), and
  // whether they are those of the state addBlocks is about to visit.
  std::vector<VertexJacobian> visitJacobians_;
  bool keptJacobians_ = false;
  // Whether a region's vertices take the per-vertex bounds of their surface pairs (until the
  // iteration stalls with them), and whether this step dropped them.
  bool regionPairBlocks_ = true, droppedPairBlocks_ = false;  // a ranked Jacobian's couplings, and as per-vertex bounds
};

}  // namespace asyncfem::detail
