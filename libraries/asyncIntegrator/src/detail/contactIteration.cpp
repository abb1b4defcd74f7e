// SPDX-License-Identifier: BSD-3-Clause
// The contact iteration of one asynchronous large step. Equation numbers refer to
// docs/asynchronous-integrator.md, section "Implicit contact".
#include "detail/contactIteration.hpp"

#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/contactBlock.hpp>
#include <cmath>
#include <string>

#include "detail/sparseBlocks.hpp"

namespace asyncfem::detail {

namespace {

/// The vertex of the first non-finite entry of values (rows: their global DOFs), or -1.
int firstNonFinite(const Eigen::MatrixXd& values, const std::vector<int>& dofs) {
  for (Eigen::Index c = 0; c < values.cols(); ++c)
    for (Eigen::Index r = 0; r < values.rows(); ++r)
      if (!std::isfinite(values(r, c))) return dofs[static_cast<std::size_t>(r)] / 3;
  return -1;
}

}  // namespace

bool LargeContactBlocks::operator==(const LargeContactBlocks& other) const {
  if (positions != other.positions) return false;
  for (std::size_t k = 0; k < values.size(); ++k)
    if (values[k] != other.values[k]) return false;
  return true;
}

void ContactIteration::setPartition(const RegionPartition& partition, int numDofs) {
  largePosition_.assign(static_cast<std::size_t>(numDofs), -1);
  regionPosition_.assign(static_cast<std::size_t>(numDofs), -1);
  const std::vector<int>& large = partition.largeDofs();
  for (std::size_t k = 0; k < large.size(); ++k)
    largePosition_[static_cast<std::size_t>(large[k])] = static_cast<int>(k);
  for (int i = 0; i < partition.numRegions(); ++i) {
    const std::vector<int>& s = partition.regionDofs(i);
    for (std::size_t k = 0; k < s.size(); ++k) regionPosition_[static_cast<std::size_t>(s[k])] = static_cast<int>(k);
  }
  vertexRegion_ = partition.vertexRegion();
}

template <class Visit>
void ContactIteration::visitStates(const std::vector<FastRegion>& regions, Visit&& visit) {
  const Eigen::VectorXd& u0 = *step_.u0;
  const Eigen::VectorXd& v0 = *step_.v0;
  const RegionPartition& partition = *step_.partition;
  u_ = u0;
  v_ = v0;
  const std::vector<int>& large = partition.largeDofs();
  for (std::size_t k = 0; k < large.size(); ++k) {
    const int dof = large[k];
    v_[dof] = v0[dof] + trialY_[static_cast<Eigen::Index>(k)];
    u_[dof] = u0[dof] + step_.hL * v_[dof];
  }
  // Region i after substep r: v_r = v_0 + x_r, u_r = u_0 + hS (r v_0 + sum_{j <= r} x_j).
  const auto setSubstep = [&](std::size_t i, int r, const Eigen::VectorXd& running) {
    const FastRegion& rb = regions[i];
    const std::vector<int>& s = partition.regionDofs(static_cast<int>(i));
    for (std::size_t k = 0; k < s.size(); ++k) {
      const auto row = static_cast<Eigen::Index>(k);
      v_[s[k]] = v0[s[k]] + trialX_[i](row, r - 1);
      u_[s[k]] = u0[s[k]] + rb.smallStep * ((r * v0[s[k]]) + running[row]);
    }
  };
  for (std::size_t i = 0; i < regions.size(); ++i) {
    sums_ = trialX_[i].rowwise().sum();
    setSubstep(i, regions[i].ratio, sums_);
  }
  const bool whole = step_.ranked != nullptr;
  if (whole) {
    prefix_.resize(regions.size());
    for (std::size_t i = 0; i < regions.size(); ++i) {
      prefix_[i].setZero(trialX_[i].rows(), trialX_[i].cols() + 1);
      for (Eigen::Index c = 0; c < trialX_[i].cols(); ++c)
        prefix_[i].col(c + 1) = prefix_[i].col(c) + trialX_[i].col(c);
    }
  }
  if (whole) {
    endU_ = u_;
    endV_ = v_;
  }
  visit(step_.t1, -1, 0);
  for (std::size_t i = 0; i < regions.size(); ++i) {
    const FastRegion& rb = regions[i];
    const int m = rb.ratio;
    running_.setZero(trialX_[i].rows());
    for (int r = 1; r < m; ++r) {
      running_ += trialX_[i].col(r - 1);
      setSubstep(i, r, running_);
      if (whole) setOthersAt(regions, i, r);
      visit(substepTime(step_.t0, step_.t1, r, m, rb.smallStep), static_cast<int>(i), r);
    }
    // Back to the end state: the next region's substeps see this one at its end.
    if (whole) {
      u_ = endU_;
      v_ = endV_;
      continue;
    }
    sums_ = trialX_[i].rowwise().sum();
    setSubstep(i, m, sums_);
  }
}

void ContactIteration::setOthersAt(const std::vector<FastRegion>& regions, std::size_t i, int r) {
  const Eigen::VectorXd& u0 = *step_.u0;
  const Eigen::VectorXd& v0 = *step_.v0;
  const RegionPartition& partition = *step_.partition;
  const double tau = r * regions[i].smallStep;  // from t0
  const std::vector<int>& large = partition.largeDofs();
  for (std::size_t k = 0; k < large.size(); ++k) {
    const int dof = large[k];
    u_[dof] = u0[dof] + tau * v_[dof];  // v_ holds v^L, constant over the step
  }
  const int m = regions[i].ratio;
  for (std::size_t j = 0; j < regions.size(); ++j) {
    if (j == i) continue;
    const FastRegion& other = regions[j];
    // Its substep c with (c - 1) hS_j < tau <= c hS_j, and the time into it.
    const int c = ((r * other.ratio) + m - 1) / m;
    const double into = tau - ((c - 1) * other.smallStep);
    const std::vector<int>& s = partition.regionDofs(static_cast<int>(j));
    for (std::size_t k = 0; k < s.size(); ++k) {
      const auto row = static_cast<Eigen::Index>(k);
      const double velocity = v0[s[k]] + trialX_[j](row, c - 1);
      v_[s[k]] = velocity;
      u_[s[k]] = u0[s[k]] + (other.smallStep * (((c - 1) * v0[s[k]]) + prefix_[j](row, c - 1))) + (into * velocity);
    }
  }
}

void ContactIteration::forcesAt(const std::vector<FastRegion>& regions) {
  const RegionPartition& partition = *step_.partition;
  const std::vector<int>& large = partition.largeDofs();
  const DynamicSystem& system = *step_.system;
  if (RankedForces* ranked = step_.ranked) {
    ranked->clear();
    // The derivatives come from the same evaluations, kept per visit for addBlocks (in the
    // order it visits), which takes them where this state is accepted.
    const bool derivatives = static_cast<bool>(system.externalForceJacobian);
    std::size_t visit = 0;
    const auto next = [&]() -> VertexJacobian* {
      if (!derivatives) return nullptr;
      if (visitJacobians_.size() <= visit) visitJacobians_.resize(visit + 1);
      return &visitJacobians_[visit++];
    };
    visitStates(regions, [&](double time, int region, int r) {
      if (region >= 0) {
        ranked->addRegion(system, region, r, time, u_, v_, next());
        return;
      }
      ranked->addLarge(system, time, u_, v_, next());
      for (std::size_t i = 0; i < regions.size(); ++i)
        ranked->addRegion(system, static_cast<int>(i), regions[i].ratio, time, u_, v_, next());
    });
    keptJacobians_ = derivatives;
    trialForceL_ = step_.hL * ranked->large;
    for (std::size_t i = 0; i < regions.size(); ++i) trialForceS_[i] = regions[i].smallStep * ranked->region[i];
    return;
  }
  if (f_.size() != u_.size()) f_.setZero(u_.size());
  visitStates(regions, [&](double time, int region, int r) {
    // At a region's substep only its own DOFs are read: with externalForceAt only its
    // vertices are evaluated (the same values), which keeps a substep's cost O(|S|).
    if (region >= 0 && system.externalForceAt) {
      const std::vector<int>& vertices = (*step_.regionVertices)[static_cast<std::size_t>(region)];
      for (const int v : vertices) f_.segment<3>(3 * static_cast<Eigen::Index>(v)).setZero();
      system.externalForceAt(time, u_, v_, vertices, f_);
    } else {
      f_.setZero(u_.size());
      system.externalForce(time, u_, v_, f_);
    }
    if (region >= 0) {
      const FastRegion& rb = regions[static_cast<std::size_t>(region)];
      const std::vector<int>& s = partition.regionDofs(region);
      for (std::size_t k = 0; k < s.size(); ++k)
        trialForceS_[static_cast<std::size_t>(region)](static_cast<Eigen::Index>(k), r - 1) = rb.smallStep * f_[s[k]];
      return;
    }
    // The end state: L's force, and every region's last substep.
    trialForceL_.resize(static_cast<Eigen::Index>(large.size()));
    for (std::size_t k = 0; k < large.size(); ++k) trialForceL_[static_cast<Eigen::Index>(k)] = step_.hL * f_[large[k]];
    for (std::size_t i = 0; i < regions.size(); ++i) {
      const FastRegion& rb = regions[i];
      const std::vector<int>& s = partition.regionDofs(static_cast<int>(i));
      trialForceS_[i].resize(static_cast<Eigen::Index>(s.size()), rb.ratio);
      for (std::size_t k = 0; k < s.size(); ++k)
        trialForceS_[i](static_cast<Eigen::Index>(k), rb.ratio - 1) = rb.smallStep * f_[s[k]];
    }
  });
}

// A ranked evaluation's pair couplings as per-vertex bounds (see addBlocks): L's vertices'
// blocks into inMatrix_ (r hS^2 K + hS C for a pair of region owner's rank at its substep r,
// hL^2 K + hL C for L's own), the owner's vertices' appended to jacobian_ while the
// iteration takes them.
void ContactIteration::takePairBounds(int owner, int r, const std::vector<FastRegion>& regions) {
  const DynamicSystem& system = *step_.system;
  couplings_.clear();
  couplings_.couplings = jacobian_.couplings;
  bounded_ = boundCouplings(couplings_);
  for (std::size_t k = 0; k < bounded_.vertices.size() && owner >= 0 && regionPairBlocks_; ++k) {
    if (vertexRegion_[static_cast<std::size_t>(bounded_.vertices[k])] != owner) continue;
    jacobian_.vertices.push_back(bounded_.vertices[k]);
    jacobian_.stiffness.push_back(bounded_.stiffness[k]);
    jacobian_.damping.push_back(bounded_.damping[k]);
  }
  const double h = owner < 0 ? step_.hL : regions[static_cast<std::size_t>(owner)].smallStep;
  const double stiffnessWeight = owner < 0 ? h * h : r * h * h;
  for (std::size_t k = 0; k < bounded_.vertices.size(); ++k) {
    const int vertex = bounded_.vertices[k];
    if (vertexRegion_[static_cast<std::size_t>(vertex)] >= 0) continue;
    const Eigen::Matrix3d block = contactStepBlock(system.freeDofs, bounded_, k, stiffnessWeight, h);
    if (block.isZero(0.0)) continue;
    int& slot = largeSlot_[static_cast<std::size_t>(vertex)];
    if (slot == 0) {
      std::array<int, 3> position{};
      for (int c = 0; c < 3; ++c)
        position[static_cast<std::size_t>(c)] = largePosition_[static_cast<std::size_t>((3 * vertex) + c)];
      inMatrix_.positions.push_back(position);
      inMatrix_.values.push_back(block);
      slot = static_cast<int>(inMatrix_.positions.size());
    } else {
      inMatrix_.values[static_cast<std::size_t>(slot - 1)] += block;
    }
  }
}

// addBlocks' blocks into the matrices: a region's weighted by the share of its substeps
// where the vertex touches, into its A^S (changedRegions_), L's into the large system.
void ContactIteration::installBlocks(SparseMatrix& largeSystem, std::vector<FastRegion>& regions,
                                     const std::vector<std::vector<std::array<int, 3>>>& positionsS,
                                     std::vector<std::vector<Eigen::Matrix3d>>& blocksS,
                                     std::vector<std::vector<Eigen::Matrix3d>>& stiffnessS) {
  const std::size_t count = regions.size();
  // A region's block weighted by the share of its substeps where the vertex touches (the
  // substeps' mean linearization; exact where it touches at all of them).
  for (std::size_t v = 0; v < blockSlot_.size(); ++v) {
    if (blockSlot_[v] == 0) continue;
    const auto i = static_cast<std::size_t>(vertexRegion_[v]);
    const double share = static_cast<double>(touches_[v]) / regions[i].ratio;
    const auto slot = static_cast<std::size_t>(blockSlot_[v] - 1);
    blocksS[i][slot] *= share;
    stiffnessS[i][slot] *= share;
  }
  changedRegions_.clear();
  for (std::size_t i = 0; i < count; ++i)
    if (regions[i].setContactBlocks(positionsS[i], blocksS[i], stiffnessS[i]))
      changedRegions_.push_back(static_cast<int>(i));
  // Each touched entry's value is kept and restored exactly by removeBlocks (adding and
  // subtracting would leave round-off in Â^L, and a resumed run would then differ).
  for (std::size_t k = 0; k < inMatrix_.positions.size(); ++k) {
    forBlockEntries(inMatrix_.positions[k], [&](int r, int c, int row, int column) {
      addKeepingEntry(largeSystem, row, column, inMatrix_.values[k](r, c), saved_, "L's system");
    });
  }
}

// The blocks of jacobian_'s vertices: L's at the end state (owner -1), a region's at the
// end state or else at the first of its substeps where it touches. With ranked terms
// (owner >= 0: region owner's terms at its substep r), the couplings of surface pairs
// enter as their per-vertex bounds: an L vertex takes r hS^2 K + hS C, the derivative of
// its share hS f(r) by its velocity increment (its position there moves by r hS per unit
// of it); the owner's vertices take theirs as any contact block, until the iteration
// stalls with them (update drops them for the rest of the step). A^S is one matrix for
// every substep, so a block taken where a light vertex strikes mid-step acts at every
// substep. Measured (docs/collision.md, the antenna striking a block at m = 30): always
// with them the iteration stalled at a relative residual of 0.1-0.2 and the runs blew up;
// never with them 3-5 of 60 steps ended unconverged (at most 0.1), but two soft boxes
// colliding head-on (tests/sceneIO/asyncSurfaceContactTest.cpp) stopped at 0.13 where the
// blocks reach 2e-4; dropping them where the iteration stalls keeps both.
void ContactIteration::addBlocks(SparseMatrix& largeSystem, std::vector<FastRegion>& regions, bool statesClear) {
  removeBlocks(largeSystem);
  const DynamicSystem& system = *step_.system;
  const std::size_t count = regions.size();
  std::vector<std::vector<std::array<int, 3>>> positionsS(count);
  std::vector<std::vector<Eigen::Matrix3d>> blocksS(count), stiffnessS(count);
  blockSlot_.assign(vertexRegion_.size(), 0);
  touches_.assign(vertexRegion_.size(), 0);
  const RankedForces* ranked = system.externalForceJacobian ? step_.ranked : nullptr;
  // The derivatives forcesAt kept at these very states (the last trial, now accepted).
  const bool kept = keptJacobians_ && !statesClear;
  keptJacobians_ = false;
  std::size_t visit = 0;
  const auto derivativesAt = [&](int owner, double time) {
    if (kept) {
      jacobian_ = visitJacobians_[visit++];
    } else {
      ranked->jacobian(system, owner, time, u_, v_, jacobian_);
    }
  };

  largeSlot_.assign(vertexRegion_.size(), 0);
  const auto take = [&](int owner, int r) {
    if (ranked && !jacobian_.couplings.empty()) takePairBounds(owner, r, regions);
    for (std::size_t k = 0; k < jacobian_.vertices.size(); ++k) {
      const int vertex = jacobian_.vertices[k];
      const int region = vertexRegion_[static_cast<std::size_t>(vertex)];
      if (owner >= 0 && region != owner) continue;
      const std::vector<int>& positionOf = region < 0 ? largePosition_ : regionPosition_;
      std::array<int, 3> position{};
      for (int c = 0; c < 3; ++c)
        position[static_cast<std::size_t>(c)] = positionOf[static_cast<std::size_t>((3 * vertex) + c)];
      // A fixed DOF's row and column are zero in the block (and its position -1).
      const double h = region < 0 ? step_.hL : regions[static_cast<std::size_t>(region)].smallStep;
      const Eigen::Matrix3d block = contactStepBlock(system.freeDofs, jacobian_, k, h * h, h);
      if (block.isZero(0.0)) continue;
      // Every region vertex in contact takes a block, soft at hS or not: A^S is one matrix
      // for all substeps, so the block (weighted below) is exact only while the vertex
      // touches at every one, and the mixing (Eq. C5) makes up the rest. Measured on the
      // k = 2e4 ball at ratio 8: blocks only where (omega hS)^2 > 4 took 2x the solves and
      // left steps unconverged.
      if (region < 0) {
        inMatrix_.positions.push_back(position);
        inMatrix_.values.push_back(block);
        continue;
      }
      ++touches_[static_cast<std::size_t>(vertex)];
      if (blockSlot_[static_cast<std::size_t>(vertex)]) continue;
      const auto i = static_cast<std::size_t>(region);
      blockSlot_[static_cast<std::size_t>(vertex)] = static_cast<int>(positionsS[i].size()) + 1;
      positionsS[i].push_back(position);
      blocksS[i].push_back(block);
      stiffnessS[i].push_back(contactStepBlock(system.freeDofs, jacobian_, k, h * h, 0.0));
    }
  };
  const auto takeBlocks = [&](double time, int only, int r) {
    if (ranked) {
      derivativesAt(only, time);
      take(only, r);
      if (only >= 0) return;
      for (std::size_t i = 0; i < count; ++i) {  // each region's terms at its last substep
        derivativesAt(static_cast<int>(i), time);
        take(static_cast<int>(i), regions[i].ratio);
      }
      return;
    }
    if (only >= 0 && system.externalForceJacobianAt) {
      system.externalForceJacobianAt(time, u_, v_, (*step_.regionVertices)[static_cast<std::size_t>(only)], jacobian_);
    } else {
      system.externalForceJacobian(time, u_, v_, jacobian_);
    }
    take(only, r);
  };
  if (!statesClear) visitStates(regions, takeBlocks);
  installBlocks(largeSystem, regions, positionsS, blocksS, stiffnessS);
}

void ContactIteration::removeBlocks(SparseMatrix& /*largeSystem*/) {
  restoreEntries(saved_);
  inMatrix_.positions.clear();
  inMatrix_.values.clear();
}

bool ContactIteration::start(const ContactStep& step, const Eigen::VectorXd& rhsL, const Eigen::VectorXd& externalL,
                             std::vector<FastRegion>& regions, SparseMatrix& largeSystem) {
  step_ = step;
  const RegionPartition& partition = *step.partition;
  const std::vector<int>& large = partition.largeDofs();
  forceL_.resize(rhsL.size());
  for (std::size_t k = 0; k < large.size(); ++k) forceL_[static_cast<Eigen::Index>(k)] = step.hL * externalL[large[k]];
  int bad = firstNonFinite(forceL_, large);
  for (std::size_t i = 0; i < regions.size() && bad < 0; ++i)
    bad = firstNonFinite(regions[i].external, partition.regionDofs(static_cast<int>(i)));
  if (bad >= 0) {
    throw NumericalError(
        "async integrator: the external force at the predicted state of the step to t = " + std::to_string(step.t1) +
        " is not finite at vertex " + std::to_string(bad) + " (implicit contact)");
  }
  baseL_ = rhsL - forceL_;
  // The accepted iterate: z = 0 (the predicted states), A_0 z - base = -base, R = -rhs.
  acceptedY_.setZero(rhsL.size());
  operatorL_ = -baseL_;
  scale_ = std::max(rhsL.lpNorm<Eigen::Infinity>(), forceL_.lpNorm<Eigen::Infinity>());
  double squares = rhsL.squaredNorm();
  const std::size_t count = regions.size();
  baseS_.resize(count);
  forceS_.resize(count);
  acceptedX_.resize(count);
  operatorS_.resize(count);
  solvedOperatorS_.resize(count);
  trialX_.resize(count);
  trialForceS_.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    const FastRegion& rb = regions[i];
    forceS_[i] = rb.smallStep * rb.external;
    baseS_[i] = rb.rhs - forceS_[i];
    acceptedX_[i].setZero(rb.rhs.rows(), rb.rhs.cols());
    operatorS_[i] = -baseS_[i];
    squares += rb.rhs.squaredNorm();
    scale_ = std::max({scale_, rb.rhs.lpNorm<Eigen::Infinity>(), forceS_[i].lpNorm<Eigen::Infinity>()});
  }
  meritNorm_ = std::sqrt(squares);
  forgetMixing();
  regionPairBlocks_ = true;
  droppedPairBlocks_ = false;
  keptJacobians_ = false;
  // The blocks at the predicted states; g = h f_ext there + J 0 is what the rhs holds.
  trialY_ = acceptedY_;
  trialX_ = acceptedX_;
  const bool clear = step.screenPredicted && predictedStatesClear();
  addBlocks(largeSystem, regions, clear);
  return clear;
}

// Eq. (C7). With the increments zero, every state addBlocks visits lies on the segment from
// u_0 to u_0 + hL v_0 (L's end state; a region's substeps at r hS v_0), so within
// hL |v_0| / 2 of the segment's midpoint. No free vertex whose midpoint is that close to an
// obstacle (with the largest half-length of all vertices) means no visited state touches
// (depth is 1-Lipschitz in the position), and where the force depends on the state only in
// contact (DynamicSystem::stateDependentOnlyInContact) every block there is zero: the
// visit of every substep's state can be skipped with the same result.
bool ContactIteration::predictedStatesClear() {
  const DynamicSystem& system = *step_.system;
  if (!system.stateDependentOnlyInContact || !system.obstacleProximity) return false;
  const Eigen::VectorXd& v0 = *step_.v0;
  double largestSquare = 0.0;
  for (Eigen::Index dof = 0; dof + 2 < v0.size(); dof += 3)
    largestSquare = std::max(largestSquare, v0.segment<3>(dof).squaredNorm());
  const double halfLength = 0.5 * step_.hL * std::sqrt(largestSquare);
  u_ = *step_.u0 + ((0.5 * step_.hL) * v0);
  return !freeVertexNearObstacle(system, u_, halfLength, nearObstacles_);
}

bool freeVertexNearObstacle(const DynamicSystem& system, const Eigen::VectorXd& positions, double radius,
                            std::vector<int>& near) {
  system.obstacleProximity(positions, (radius * (1.0 + 1e-9)) + 1e-12, near);
  for (const int vertex : near)
    for (int c = 0; c < 3; ++c)
      if (!system.freeDofs.isFixed((3 * vertex) + c)) return true;
  return false;
}

// y += B x for L's blocks (rows and columns of L).
void ContactIteration::addBlockProduct(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  for (std::size_t b = 0; b < inMatrix_.positions.size(); ++b) {
    forBlockEntries(inMatrix_.positions[b],
                    [&](int r, int c, int row, int column) { y[row] += inMatrix_.values[b](r, c) * x[column]; });
  }
}

// The residual of the trial state (trialY_, trialX_) at theta along the update: its
// largest entry (worstVertex_ where), and its 2-norm into merit.
double ContactIteration::trialResidual(const std::vector<FastRegion>& regions, double theta, double& merit) {
  const RegionPartition& partition = *step_.partition;
  const std::vector<int>& large = partition.largeDofs();
  forcesAt(regions);
  double residual = 0.0;
  double squares = 0.0;
  int worst = -1;
  const auto record = [&](double value, int dof) {
    squares += value * value;
    if (!(std::abs(value) <= residual)) {  // NaN included: it is reported
      residual = std::abs(value);
      worst = dof / 3;
    }
  };
  for (std::size_t k = 0; k < large.size(); ++k) {
    const auto row = static_cast<Eigen::Index>(k);
    const double op = operatorL_[row] + theta * (solvedOperatorL_[row] - operatorL_[row]);
    record(op - trialForceL_[row], large[k]);
  }
  for (std::size_t i = 0; i < regions.size(); ++i) {
    const std::vector<int>& s = partition.regionDofs(static_cast<int>(i));
    for (Eigen::Index r = 0; r < trialForceS_[i].cols(); ++r)
      for (std::size_t k = 0; k < s.size(); ++k) {
        const auto row = static_cast<Eigen::Index>(k);
        const double op = operatorS_[i](row, r) + theta * (solvedOperatorS_[i](row, r) - operatorS_[i](row, r));
        record(op - trialForceS_[i](row, r), s[k]);
      }
  }
  worstVertex_ = worst;
  merit = std::sqrt(squares);
  return residual;
}

// The state at theta from the accepted one toward Y and each region's x, and its residual.
double ContactIteration::tryState(const std::vector<FastRegion>& regions, const Eigen::VectorXd& Y, double theta,
                                  double& merit) {
  const RegionPartition& partition = *step_.partition;
  trialY_ = acceptedY_ + theta * (Y - acceptedY_);
  for (std::size_t i = 0; i < regions.size(); ++i) trialX_[i] = acceptedX_[i] + theta * (regions[i].x - acceptedX_[i]);
  int worst = firstNonFinite(trialY_, partition.largeDofs());
  for (std::size_t i = 0; i < regions.size() && worst < 0; ++i)
    worst = firstNonFinite(trialX_[i], partition.regionDofs(static_cast<int>(i)));
  if (worst >= 0) {
    worstVertex_ = worst;
    return std::nan("");
  }
  return trialResidual(regions, theta, merit);
}

double ContactIteration::update(std::vector<FastRegion>& regions, Eigen::VectorXd& Y, SparseMatrix& largeSystem,
                                Eigen::VectorXd& rhsL) {
  // A_0 z - base at the solve's z (Eq. C4): the force terms it used less the contact
  // blocks' part J z (L's blocks B Y; a region's hS^2 K_c and hS C_c terms).
  solvedOperatorL_ = forceL_;
  blockProduct_.setZero(Y.size());
  addBlockProduct(Y, blockProduct_);
  solvedOperatorL_ -= blockProduct_;
  for (std::size_t i = 0; i < regions.size(); ++i) {
    solvedOperatorS_[i] = -forceS_[i];
    regions[i].addContactProduct(regions[i].x, solvedOperatorS_[i]);
    solvedOperatorS_[i] = -solvedOperatorS_[i];
  }
  // Anderson's combination of the last solves (Eq. C5), taken whole when it lowers |R|_2;
  // else the solve's own state, backtracked: z = z_k + theta (z_solve - z_k), A_0 z - base
  // interpolated alike (it is affine in z), halved while |R|_2 rises above the accepted
  // iterate's.
  double theta = 1.0, residual = 0.0, merit = 0.0;
  bool accepted = false;
  if (mix(Y, regions)) {
    residual = tryState(regions, Y, 1.0, merit);
    accepted = std::isfinite(residual) && merit < meritNorm_;
    if (!accepted) unmix(Y, regions);
  }
  for (int halvings = 0; !accepted; ++halvings) {
    residual = tryState(regions, Y, theta, merit);
    if (!std::isfinite(residual)) return std::nan("");  // reported at worstVertex_
    if (merit < meritNorm_ || halvings == kMaxHalvings) break;
    theta *= 0.5;
  }
  // A stalled iteration (the solve's own step had to be cut to an eighth or less) drops the
  // fast regions' pair blocks for the rest of the step, and the solves mixed so far (made
  // with them). See addBlocks.
  if (!accepted && theta <= 0.125 && regionPairBlocks_ && step_.ranked != nullptr) {
    regionPairBlocks_ = false;
    droppedPairBlocks_ = true;
    forgetMixing();
  }
  // Accept z (the caller's state becomes it), take the contact blocks there and set the
  // next solve's force terms: g = G(z) + J z (Eq. C3).
  meritNorm_ = merit;
  operatorL_ += theta * (solvedOperatorL_ - operatorL_);
  acceptedY_ = trialY_;
  Y = trialY_;
  for (std::size_t i = 0; i < regions.size(); ++i) {
    operatorS_[i] += theta * (solvedOperatorS_[i] - operatorS_[i]);
    acceptedX_[i] = trialX_[i];
    regions[i].x = trialX_[i];
  }
  addBlocks(largeSystem, regions);
  for (std::size_t i = 0; i < regions.size(); ++i) {
    forceS_[i] = trialForceS_[i];
    regions[i].addContactProduct(acceptedX_[i], forceS_[i]);
    regions[i].rhs = baseS_[i] + forceS_[i];
  }
  forceL_ = trialForceL_;
  addBlockProduct(acceptedY_, forceL_);
  rhsL = baseL_ + forceL_;
  return scale_ > 0.0 ? residual / scale_ : residual;
}

}  // namespace asyncfem::detail
