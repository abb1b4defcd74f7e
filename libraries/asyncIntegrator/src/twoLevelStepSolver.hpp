// SPDX-License-Identifier: BSD-3-Clause
// The two-level step solvers (every fast region coupled only to L): the structured Schur
// solve (Eqs. A13-A15) and its naive LU reference share the blocks, the right-hand sides and
// the recovery of the end state; they differ in how the coupled block system is factored
// and solved. Its parts, one concept per file: twoLevelStepSolver.cpp (set-up, blocks and
// factors, one step), structuredStep.cpp (right-hand sides, Schur solve, recovery),
// laggedSchur.cpp, quickSetUp.cpp, implicitContact.cpp, regionDistribution.cpp. Private to
// the library.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <asyncfem/asyncIntegrator/asyncOptions.hpp>
#include <asyncfem/asyncIntegrator/detail/vertexRotations.hpp>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/asyncIntegrator/stepSolver.hpp>
#include <asyncfem/dynamics/dynamicSystem.hpp>
#include <cmath>
#include <exception>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include "detail/contactIteration.hpp"
#include "detail/fastRegion.hpp"
#include "detail/naiveSolver.hpp"
#include "detail/schurSolver.hpp"
#include "detail/sparseBlocks.hpp"
#include "stepSolvers.hpp"

namespace asyncfem::detail {

using SparseMatrix = Eigen::SparseMatrix<double>;

// What a two-level solver keeps for its partition.
struct TwoLevelState {
  // What the model is (set when the integrator is made; symmetry checked at the first
  // linear set-up).
  struct Model {
    bool linear = true;
    bool perElementTangent = false;  // interface element tangents from the force model (else cached linear ones)
    // Linear forces with a symmetric K: f_int(u_0) = K u_0 and K v_0 are taken row by row
    // (row i = column i) on the DOFs that need them, and L's rows need only
    // K (u_0 + (beta + hL) v_0), as in single-rate backward Euler.
    bool symmetricStiffness = false;
    bool symmetryChecked = false;
  } model;
  // What has been built for this timestep and partition.
  struct Build {
    bool factorsCurrent = false;  // linear forces: blocks and factors built for this timestep and partition
    bool settingUp = false;       // the build under way is a set-up (for AsyncRunStats)
    // Linear forces: K is in stiffness (constant), so a new partition need not evaluate it again.
    bool stiffnessKnown = false;
    bool cutLL = false;  // L's blocks extracted once per partition; later only their values are updated
    // M and K share one pattern (element matrices on the same mesh): K^{LL} is cut with
    // massLL's map and stiffLL stays empty. Checked once (-1: not yet).
    int sharedPattern = -1;
  } build;
  SparseMatrix stiffness;  // full 3n x 3n tangent K(u_0)
  Eigen::VectorXd internalForce;
  std::vector<detail::FastRegion> regions;
  SubmatrixExtractor massLL, stiffLL;
  SparseMatrix Mll, Kll;     // M^{LL} (constant), K^{LL}; only when M and K have different patterns
  SparseMatrix largeSystem;  // Â^L
  detail::SchurSolver schur;
  detail::VertexRotations rotations;  // since the last rebuild (laggedSchurRotation)
  detail::NaiveSolver naive;
  // The lagged factor of H^{LL*} (AsyncOptions::KeptFactors::laggedSchur) and its rent-or-buy prices
  // (flops, set at each full rebuild).
  struct LaggedFactor {
    bool lagging = false;          // this step refactored A^S but keeps Z and H^{LL*} from an earlier tangent
    bool lastRebuildFull = false;  // built with Z (not refreshed): the next rebuild the rule asks for may be a refresh
    bool recoverFromProbes = false;  // the lagged solve converged with its tracker: recovery from the summed probes
    double iterationFlops = 0.0;     // one refinement iteration
    double rebuildFlops = 0.0;       // one rebuild
    double rent = 0.0;               // the iterations paid since the last rebuild
  } lagged;
  // Quick set-up (AsyncOptions::KeptFactors::quickSetUp): L's system is solved on the whole system's
  // factor until the iterations' extra flops reach the priced cost of the rebuild (Eq. Q4).
  struct QuickPath {
    bool active = false;
    double extraFlops = 0.0;
  } quickPath;
  // Per-step buffers (full 3n, or |L|).
  Eigen::VectorXd stiffVelocity, massVelocity, stateForce, predicted, newU, newV, work;
  Eigen::VectorXd rhsL, rhsSchur, Y;
  std::vector<double> interfaceSum;  // regionDistribution: every region's interface rows, summed
  const Eigen::VectorXd* externalL = nullptr;
  // External forces at the distinct times of one large step (shared by regions whose
  // substeps fall on the same times), valid for one step.
  std::vector<double> forceTimes;
  std::vector<Eigen::VectorXd> forceValues;
  std::size_t forcesUsed = 0;
  // Each region's vertices with free DOFs (ascending), and a region's force at one
  // predicted substep: where the system has externalForceAt, substeps evaluate only them.
  std::vector<std::vector<int>> regionVertices;
  Eigen::VectorXd regionForce;
  // Where the system has externalForceOfRank (surface contact): the force terms split by
  // rank, and L's external force built from them (full size, L's entries).
  detail::RankedForces ranked;
  Eigen::VectorXd rankedL;
  // Implicit contact (DynamicSystem::externalForceJacobian): the contact iteration, and
  // whether a region's A^S holds contact blocks that Z and H^{LL*} were not built with.
  detail::ContactIteration contact;
  struct ContactStep {
    bool correctionsStale = false;  // a region's A^S holds contact blocks Z and H^{LL*} were not built with
    bool certifying = false;        // the first solve recovers end states only, for the certificate (Eq. C6)
  } contactStep;
  // The first solve of an implicit contact step recovers end states only, for the
  // certificate (Eq. C6): each DOF's interval of displacements over the step's states, the
  // boxes' centres, the interface's share of each vertex's radius (squared) and the
  // vertices near an obstacle.
  Eigen::VectorXd lowest, highest, centred, runningPath;
  std::vector<double> reachSquares;
  std::vector<int> nearObstacles;
  // Each region's contact blocks in A^S when Z and H^{LL*} were last built (none at a
  // set-up): a step whose blocks are back to them (contact over, A^S refactored to what Z
  // was built from) has current corrections again, without a rebuild.
  struct BuiltBlocks {
    std::vector<std::array<int, 3>> positions;
    std::vector<Eigen::Matrix3d> blocks, stiffness;
  };
  std::vector<BuiltBlocks> schurBlocks;

  void noteSchurBlocks() {
    schurBlocks.resize(regions.size());
    for (std::size_t i = 0; i < regions.size(); ++i)
      schurBlocks[i] = {regions[i].contactPositions, regions[i].contactBlocks, regions[i].contactStiffness};
  }
  bool blocksAsBuilt() const {
    for (std::size_t i = 0; i < regions.size(); ++i) {
      const detail::FastRegion& rb = regions[i];
      if (i >= schurBlocks.size()) {
        if (rb.hasContactBlocks()) return false;
        continue;
      }
      const BuiltBlocks& built = schurBlocks[i];
      if (rb.contactPositions != built.positions || rb.contactBlocks != built.blocks ||
          rb.contactStiffness != built.stiffness)
        return false;
    }
    return true;
  }

  bool rowProducts() const { return model.linear && model.symmetricStiffness; }
  /// f_ext at time and state (u, v0), evaluated in this thread (the callback need not be
  /// thread-safe): once per distinct time at the start state u0, always anew at a predicted one.
  const Eigen::VectorXd& forceAt(const DynamicSystem& system, double time, const Eigen::VectorXd& u,
                                 const Eigen::VectorXd& u0, const Eigen::VectorXd& v0) {
    if (&u == &u0) {
      for (std::size_t k = 0; k < forcesUsed; ++k)
        if (forceTimes[k] == time) return forceValues[k];
    }
    if (forcesUsed == forceValues.size()) {
      forceValues.emplace_back();
      forceTimes.push_back(0.0);
    }
    Eigen::VectorXd& f = forceValues[forcesUsed];
    forceTimes[forcesUsed] = &u == &u0 ? time : std::nan("");  // predicted states are never shared
    ++forcesUsed;
    f.setZero(u0.size());
    system.externalForce(time, u, v0, f);
    return f;
  }
};

/// The structured Schur solve (kind structuredSchur) or the naive LU of the whole block
/// system (kind naiveLU) for a partition whose regions each couple only to L.
class TwoLevelStepSolver final : public StepSolver {
 public:
  TwoLevelStepSolver(AsyncStepSolver kind, const StepContext& context);
  ~TwoLevelStepSolver() override;

  AsyncStepSolver kind() const override { return kind_; }
  void setUp() override;
  void invalidateFactors() override { impl_->build.factorsCurrent = false; }
  StepEnd step(double t0, double t1) override;
  long long factorNonZeros() const override;
  void reportLines(std::vector<std::string>& lines) const override;
  /// AsyncBackwardEuler::solveFloorSeconds().
  double solveFloorSeconds(int repeats);

 private:
  using Impl = TwoLevelState;
  // Set-up, blocks and factors (twoLevelStepSolver.cpp).
  void refactor();
  void assembleBlocks();
  void subtractInterfaceStiffness();
  void fullSchurRebuild();
  void refactorLargeSystem();
  void evaluateStartOfStep();
  void gatherExternalForces(double t0, double t1);
  /// gatherExternalForces at the predicted states with the force split by rank.
  void gatherRankedForces(double t0, double t1, bool implicit);
  void countSolves();
  // One step's right-hand sides, solve and recovery (structuredStep.cpp).
  void largeRightHandSide();
  void addInterfaceVelocityTerms();
  void regionRightHandSides();
  void solveStructured();
  void recoverRegion(int region);
  void substituteRegion(int i);
  void assembleNewState(double t0, double t1);
  // The lagged factor of H^{LL*} (laggedSchur.cpp).
  void priceLaggedFactor();
  void refreshLaggedFactor();
  void keepLaggedFactor();
  /// Whether the lagged factor preconditions turned with the body (laggedSchurRotation).
  bool turnsLaggedFactor() const;
  void applySchur(const Eigen::VectorXd& y, Eigen::VectorXd& out);
  void sumProbeSubstitutions(int threads, double coefficient, bool reset);
  // The quick set-up (quickSetUp.cpp).
  void borrowWholeFactor();
  void solveOnWholeFactor();
  // Implicit contact and its certificate (implicitContact.cpp).
  void solveWithImplicitContact(double t0, double t1);
  /// Implicit contact may end a step after one solve (AsyncOptions::Contact::certifyContactFree).
  bool certifiesContactFree() const;
  bool contactFreeCertified();
  void refactorContactRegions();
  bool rebuildWithoutRegionBlocks();
  // AsyncOptions::Processes::regionDistribution (regionDistribution.cpp).
  bool distributed() const { return static_cast<bool>(options_.processes.regionDistribution.sum); }
  void assignRegionOwners();
  void priceSubstitutions();
  void shareCorrections();
  void subtractOwnedInterfaceRows(Eigen::VectorXd& target);
  void shareRecoveries();
  void runOwnedTasks(int threads, const std::function<void(int)>& task);
  void holdFailure(int region);
  void sumOverProcesses(std::vector<double>& values);

  AsyncStepSolver kind_;
  std::unique_ptr<Impl> impl_;
  // Distributed: the first failure of this process's region work, held until the next sum
  // over the processes, where every process learns of it and all stop (none waits).
  std::exception_ptr heldFailure_;
  int heldFailureRegion_ = -1;
};

}  // namespace asyncfem::detail
