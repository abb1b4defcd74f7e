// SPDX-License-Identifier: BSD-3-Clause
// Equation numbers refer to docs/asynchronous-integrator.md, "Nested and touching regions".
#include "detail/hierarchySystem.hpp"

#include <Eigen/OrderingMethods>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <set>
#include <string>
#include <tuple>

#include "detail/meshElements.hpp"
#include "detail/sparseBlocks.hpp"
#include "detail/structuredHierarchySolve.hpp"

namespace asyncfem::detail {

namespace {

using Triplets = std::vector<Eigen::Triplet<double>>;
/// Element e's block (elementDofs() square) at its vertices' DOFs.
void appendElement(const TetMesh& mesh, int e, const Eigen::MatrixXd& block, Triplets& out) {
  const int size = elementDofs(mesh);
  for (int b = 0; b < size; ++b)
    for (int a = 0; a < size; ++a) out.emplace_back(elementDof(mesh, e, a), elementDof(mesh, e, b), block(a, b));
}

SparseMatrix fromTriplets(int size, const Triplets& triplets) {
  SparseMatrix out(size, size);
  out.setFromTriplets(triplets.begin(), triplets.end());
  out.makeCompressed();
  return out;
}

/// |A - B|_max / |A|_max.
double relativeDifference(const SparseMatrix& a, const SparseMatrix& b) {
  const SparseMatrix difference = a - b;
  return largestMagnitude(difference) / std::max(largestMagnitude(a), 1e-300);
}

/// Relative tolerance for "the same matrix summed in another order" (round-off is ~1e-15;
/// another material, mass lumping or a scaled matrix differs by far more).
constexpr double kSameMatrix = 1e-10;
/// Most velocity unknowns the step system may have (its LU must fit in memory).
constexpr long long kMaxUnknowns = 1LL << 28;

}  // namespace

HierarchySystem::HierarchySystem(const TetMesh& mesh, const DynamicSystem& system, const RegionPartition& partition,
                                 NestedSolve solve)
    : mesh_(mesh),
      system_(system),
      tangents_(mesh, *system.forceModel, "nested async regions"),
      elementCounts_(partition.elementCounts()),
      units_(partition.units()),
      requested_(solve) {
  if (units_ == 0) {
    throw ValidationError("nested async regions: the least common multiple of the ratios exceeds " +
                          std::to_string(RegionPartition::kMaxUnits) + "; use ratios that divide one another");
  }
  free_ = system.freeDofs.freeToFull();
  freeIndex_ = system.freeDofs.fullToFree();
  dofCount_.resize(free_.size());
  offset_.assign(free_.size() + 1, 0);
  long long total = 0;
  for (std::size_t d = 0; d < free_.size(); ++d) {
    dofCount_[d] = partition.vertexCounts()[static_cast<std::size_t>(free_[d] / 3)];
    total += dofCount_[d];
    if (total > kMaxUnknowns) {
      throw ValidationError("nested async regions: the step system would have more than " +
                            std::to_string(kMaxUnknowns) + " velocity unknowns; use smaller regions or ratios");
    }
    offset_[d + 1] = static_cast<int>(total);
  }
  velocityUnknowns_ = static_cast<int>(total);
  std::set<long long> ends;
  for (int count : std::set<int>(dofCount_.begin(), dofCount_.end()))
    for (long long j = 1; j <= count; ++j) ends.insert(j * (units_ / count));
  stepEndUnits_.assign(ends.begin(), ends.end());
  if (!tangents_.perElement()) checkLinearStiffness();
  chooseElementMass();
  chooseOrder();
  if (solve == NestedSolve::structured ||
      (solve == NestedSolve::automatic && StructuredHierarchySolve::applies(dofCount_))) {
    structured_ = std::make_unique<StructuredHierarchySolve>(dofCount_, offset_, velocityUnknowns_);
  } else if (solve == NestedSolve::automatic) {
    fallbackReason_ = "the step counts do not divide one another in a chain";
  }
}

HierarchySystem::~HierarchySystem() = default;

void HierarchySystem::checkLinearStiffness() {
  Triplets triplets;
  for (int e = 0; e < mesh_.numElements(); ++e) {
    appendElement(mesh_, e, tangents_.linear(e), triplets);
  }
  SparseMatrix model = system_.forceModel->createStiffnessMatrix();
  system_.forceModel->tangentStiffness(Eigen::VectorXd::Zero(mesh_.numDofs()), model);
  const double difference = relativeDifference(model, fromTriplets(mesh_.numDofs(), triplets));
  if (!(difference <= kSameMatrix)) {
    throw ValidationError(
        "nested async regions: the force model gives no element tangent and its K differs from the mesh's linear "
        "FEM stiffness (relative difference " +
        std::to_string(difference) + "): build it from this mesh");
  }
}

Eigen::MatrixXd HierarchySystem::elementMass(int e) const {
  return massOf(mesh_, e, elementMass_ == ElementMass::lumped);
}

// Mass-proportional damping is an element force (Eq. N2), so each element's mass is needed:
// whichever of the mesh's consistent or lumped element masses sums to the system's M.
void HierarchySystem::chooseElementMass() {
  if (system_.rayleighMass == 0.0) return;
  for (ElementMass kind : {ElementMass::consistent, ElementMass::lumped}) {
    elementMass_ = kind;
    Triplets triplets;
    for (int e = 0; e < mesh_.numElements(); ++e) appendElement(mesh_, e, elementMass(e), triplets);
    if (relativeDifference(system_.mass, fromTriplets(mesh_.numDofs(), triplets)) <= kSameMatrix) return;
  }
  elementMass_ = ElementMass::none;
  throw ValidationError(
      "nested async regions: Rayleigh mass damping (alpha) is applied per element, but the system's mass matrix is "
      "neither the mesh's consistent nor its lumped mass");
}

void HierarchySystem::groupElements(const Eigen::VectorXd& u) {
  std::map<int, Triplets> stiffness, mass;
  Eigen::MatrixXd tangent;
  const bool needMass = elementMass_ != ElementMass::none && massByCount_.empty();
  for (int e = 0; e < mesh_.numElements(); ++e) {
    const int count = elementCounts_[static_cast<std::size_t>(e)];
    tangents_.tangent(u, e, tangent);
    appendElement(mesh_, e, tangent, stiffness[count]);
    if (needMass) appendElement(mesh_, e, elementMass(e), mass[count]);
  }
  stiffnessByCount_.clear();
  for (const auto& [count, triplets] : stiffness) stiffnessByCount_[count] = fromTriplets(mesh_.numDofs(), triplets);
  for (const auto& [count, triplets] : mass) massByCount_[count] = fromTriplets(mesh_.numDofs(), triplets);
}

// Eq. N1: w_{d,j} - w_{d,j-1} - h_d v_{d,j} = 0 (w_{d,0} = 0).
void HierarchySystem::addPositionRows(Triplets& out) const {
  for (int d = 0; d < static_cast<int>(free_.size()); ++d) {
    const double h = largeStep_ / dofCount_[static_cast<std::size_t>(d)];
    for (long long j = 1; j <= dofCount_[static_cast<std::size_t>(d)]; ++j) {
      const int row = displacementRow(d, j);
      out.emplace_back(row, row, 1.0);
      if (j >= 2) out.emplace_back(row, displacementRow(d, j - 1), -1.0);
      out.emplace_back(row, velocityRow(d, j), -h);
    }
  }
}

// Eq. N3: sum_p M_dp (v_p(b) - v_p(a)) over d's step (a, b]; v_p(0) goes to the right side.
void HierarchySystem::addMassRows(Triplets& out) const {
  const SparseMatrix& mass = system_.mass;
  for (int d = 0; d < static_cast<int>(free_.size()); ++d) {
    const long long sd = unitsPerStep(d);
    for (SparseMatrix::InnerIterator it(mass, free_[static_cast<std::size_t>(d)]); it; ++it) {
      const int p = freeIndex_[static_cast<std::size_t>(it.row())];  // M is symmetric: column d = row d
      if (p < 0) continue;
      const long long sp = unitsPerStep(p);
      for (long long j = 1; j <= dofCount_[static_cast<std::size_t>(d)]; ++j) {
        const long long jb = stepContaining(j * sd, sp), ja = stepContaining((j - 1) * sd, sp);
        if (jb == ja) continue;  // p's velocity is constant over d's step
        out.emplace_back(velocityRow(d, j), velocityRow(p, jb), it.value());
        if (ja >= 1) out.emplace_back(velocityRow(d, j), velocityRow(p, ja), -it.value());
      }
    }
  }
}

// Eq. N2/N4: the elements of count g are evaluated at t_q = q hL / g, q = 1..g, with weight
// h_g = hL / g; the impulse on DOF d goes to the row of d's step that t_q falls in. The
// displacement of p at t_q is w_{p,jp-1} + (t_q - t_{p,jp-1}) v_{p,jp} (Eq. N1).
void HierarchySystem::addElementRows(int count, const SparseMatrix& matrix, bool displacementTerm,
                                     Triplets& out) const {
  const long long sg = units_ / count;
  const double hg = largeStep_ / count;
  const double unit = largeStep_ / static_cast<double>(units_);
  for (Eigen::Index column = 0; column < matrix.outerSize(); ++column) {
    const int p = freeIndex_[static_cast<std::size_t>(column)];
    if (p < 0) continue;
    const long long sp = unitsPerStep(p);
    for (SparseMatrix::InnerIterator it(matrix, column); it; ++it) {
      const int d = freeIndex_[static_cast<std::size_t>(it.row())];
      if (d < 0) continue;
      const long long sd = unitsPerStep(d);
      for (long long q = 1; q <= count; ++q) {
        const long long tq = q * sg;
        const int row = velocityRow(d, stepContaining(tq, sd));
        const long long jp = stepContaining(tq, sp);
        if (!displacementTerm) {
          out.emplace_back(row, velocityRow(p, jp), hg * it.value());
          continue;
        }
        if (jp >= 2) out.emplace_back(row, displacementRow(p, jp - 1), hg * it.value());
        const double elapsed = static_cast<double>(tq - (jp - 1) * sp) * unit;
        out.emplace_back(row, velocityRow(p, jp), hg * it.value() * elapsed);
      }
    }
  }
}

void HierarchySystem::build(const Eigen::VectorXd& u, double largeStep, IntegratorStats& stats) {
  Stopwatch forces, assembly, factorization;
  forces.start();
  groupElements(u);
  stats.forceSeconds += forces.stop();
  assembly.start();
  largeStep_ = largeStep;
  Triplets triplets;
  addPositionRows(triplets);
  addMassRows(triplets);
  for (const auto& [count, stiffness] : stiffnessByCount_) {
    addElementRows(count, stiffness, true, triplets);
    if (!system_.damped()) continue;
    SparseMatrix damping = system_.rayleighStiffness * stiffness;
    if (elementMass_ != ElementMass::none) damping += system_.rayleighMass * massByCount_.at(count);
    addElementRows(count, damping, false, triplets);
  }
  matrix_ = fromTriplets(static_cast<int>(unknowns()), triplets);
  stats.assemblySeconds += assembly.stop();
  factorization.start();
  factorize(stats);
  stats.factorizationSeconds += factorization.stop();
}

// Eq. N8: a fast DOF's chain of steps is eliminated in time order, before the slower DOFs it
// couples to (L last): each level's Schur complement lands on the interface of the next
// slower one, as in the structured solve (A13). Within one time, an AMD order of the
// free DOFs' stiffness graph keeps L's own fill that of a sparse Cholesky factor.
void HierarchySystem::chooseOrder() {
  const auto nf = static_cast<int>(free_.size());
  SparseMatrix graph = system_.forceModel->createStiffnessMatrix();
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index column = 0; column < graph.outerSize(); ++column)
    for (SparseMatrix::InnerIterator it(graph, column); it; ++it) {
      const int a = freeIndex_[static_cast<std::size_t>(it.row())], b = freeIndex_[static_cast<std::size_t>(column)];
      if (a >= 0 && b >= 0) entries.emplace_back(a, b, 1.0);
    }
  SparseMatrix freeGraph(nf, nf);
  freeGraph.setFromTriplets(entries.begin(), entries.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> amd;
  Eigen::AMDOrdering<int>()(freeGraph, amd);  // amd.indices()[position] = free DOF
  std::vector<int> spatialRank(free_.size());
  for (int position = 0; position < nf; ++position)
    spatialRank[static_cast<std::size_t>(amd.indices()[position])] = position;
  struct Key {
    long long time;
    int rank, kind, unknown;
  };
  std::vector<Key> keys;
  keys.reserve(static_cast<std::size_t>(unknowns()));
  for (int d = 0; d < nf; ++d)
    for (long long j = 1; j <= dofCount_[static_cast<std::size_t>(d)]; ++j) {
      const long long time = j * unitsPerStep(d);
      keys.push_back({time, spatialRank[static_cast<std::size_t>(d)], 0, velocityRow(d, j)});
      keys.push_back({time, spatialRank[static_cast<std::size_t>(d)], 1, displacementRow(d, j)});
    }
  std::sort(keys.begin(), keys.end(), [](const Key& a, const Key& b) {
    return std::tie(a.time, a.rank, a.kind) < std::tie(b.time, b.rank, b.kind);
  });
  order_.resize(static_cast<Eigen::Index>(keys.size()));
  for (std::size_t position = 0; position < keys.size(); ++position)
    order_.indices()[keys[position].unknown] = static_cast<int>(position);
}

// The structured solve (Eqs. N9-N12) when it applies. Its first factor is checked on a
// known solution: an error above 1e-6 means the system lacks the structure it assumes,
// which NestedSolve::automatic answers with the LU (and the report says why).
void HierarchySystem::factorize(IntegratorStats& stats) {
  if (structured_) {
    try {
      structured_->factor(matrix_, stats);
      if (!structureChecked_) {
        const double error = structured_->checkEndState(matrix_);
        structureChecked_ = true;
        if (!(error <= 1e-6)) {
          throw NumericalError("the structured solve missed a known solution by " + std::to_string(error) +
                               " (relative)");
        }
      }
      factorNonZeros_ = structured_->storedEntries();
      return;
    } catch (const Error& e) {
      if (requested_ == NestedSolve::structured) throw;
      fallbackReason_ = e.what();
      structured_.reset();
    }
  }
  factorizeLU(stats);
}

void HierarchySystem::scalePositionRows() {
  // Position rows (Eq. N5) are in metres; scaled by M_dd / h_d they weigh like the velocity
  // rows (momentum), so the LU's diagonal pivots stay the natural ones.
  rowScale_ = Eigen::VectorXd::Ones(unknowns());
  for (int d = 0; d < static_cast<int>(free_.size()); ++d) {
    const double h = largeStep_ / dofCount_[static_cast<std::size_t>(d)];
    const int dof = free_[static_cast<std::size_t>(d)];
    for (long long j = 1; j <= dofCount_[static_cast<std::size_t>(d)]; ++j)
      rowScale_[displacementRow(d, j)] = system_.mass.coeff(dof, dof) / h;
  }
}

void HierarchySystem::factorizeLU(IntegratorStats& stats) {
  scalePositionRows();
  const SparseMatrix scaled = rowScale_.asDiagonal() * matrix_;
  SparseMatrix ordered = order_ * scaled * order_.transpose();
  ordered.makeCompressed();
  if (!analyzed_) {
    // Diagonal pivots unless one is below 1e-3 of its column (the scaled rows make the
    // diagonal the natural pivot; partial pivoting would undo the order).
    lu_.setPivotThreshold(1e-3);
    lu_.analyzePattern(ordered);
    analyzed_ = true;
  }
  lu_.factorize(ordered);
  if (lu_.info() != Eigen::Success) {
    throw NumericalError("nested async regions: the step system is singular (" + lu_.lastErrorMessage() + ")");
  }
  factorNonZeros_ = lu_.nnzL() + lu_.nnzU();
  ++stats.factorizations;
}

void HierarchySystem::loadRightHandSide(const Eigen::VectorXd& v0, const Eigen::VectorXd& internalForce,
                                        const std::map<long long, Eigen::VectorXd>& external,
                                        Eigen::VectorXd& rhs) const {
  rhs.setZero(unknowns());
  const Eigen::VectorXd momentum = system_.mass * v0;
  for (int d = 0; d < static_cast<int>(free_.size()); ++d) {
    const int dof = free_[static_cast<std::size_t>(d)];
    const double h = largeStep_ / dofCount_[static_cast<std::size_t>(d)];
    for (long long j = 1; j <= dofCount_[static_cast<std::size_t>(d)]; ++j) {
      const auto f = external.find(j * unitsPerStep(d));
      const double load = f == external.end() ? 0.0 : f->second[dof];
      rhs[velocityRow(d, j)] = h * (load - internalForce[dof]);
    }
    rhs[velocityRow(d, 1)] += momentum[dof];  // the v_p(0) of every mass-coupled p
  }
}

// Eq. N3's right-hand side (loadRightHandSide), solved with the kept factor.
void HierarchySystem::step(const Eigen::VectorXd& u0, const Eigen::VectorXd& v0, const Eigen::VectorXd& internalForce,
                           const std::map<long long, Eigen::VectorXd>& external, Eigen::VectorXd& u1,
                           Eigen::VectorXd& v1, IntegratorStats& stats) {
  Stopwatch solve;
  solve.start();
  loadRightHandSide(v0, internalForce, external, rhs_);
  if (structured_) {
    structured_->solve(rhs_, solution_, false);
    solutionComplete_ = false;
  } else {
    const Eigen::VectorXd ordered = order_ * rowScale_.cwiseProduct(rhs_);
    solution_ = order_.transpose() * lu_.solve(ordered);
    solutionComplete_ = true;
  }
  endState(u0, v0, u1, v1);
  ++stats.solvedRightHandSides;
  // As the other integrators count: the substitutions with factors (LU: one multiply-add
  // per factor entry), not the sparse products around them.
  stats.solveFlops += structured_ ? structured_->substitutionFlops() : 2.0 * static_cast<double>(factorNonZeros_);
  stats.solveSeconds += solve.stop();
}

void HierarchySystem::endState(const Eigen::VectorXd& u0, const Eigen::VectorXd& v0, Eigen::VectorXd& u1,
                               Eigen::VectorXd& v1) const {
  u1 = u0;
  v1 = v0;
  for (int d = 0; d < static_cast<int>(free_.size()); ++d) {
    const int dof = free_[static_cast<std::size_t>(d)];
    const long long last = dofCount_[static_cast<std::size_t>(d)];
    u1[dof] = u0[dof] + solution_[displacementRow(d, last)];
    v1[dof] = solution_[velocityRow(d, last)];
  }
}

void HierarchySystem::completeSolution() const {
  if (solutionComplete_ || !structured_ || solution_.size() == 0) return;
  structured_->solve(rhs_, solution_, true);
  solutionComplete_ = true;
}

std::string HierarchySystem::solveDescription() const {
  if (structured_) return "structured solve (" + structured_->describe() + ")";
  return "LU factor " + std::to_string(factorNonZeros_) + " non-zeros" +
         (fallbackReason_.empty() ? "" : " (structured solve not used: " + fallbackReason_ + ")");
}

Eigen::VectorXd HierarchySystem::velocities(int freeDof) const {
  completeSolution();
  if (solution_.size() == 0) return {};
  return solution_.segment(velocityRow(freeDof, 1), dofCount_[static_cast<std::size_t>(freeDof)]);
}

Eigen::VectorXd HierarchySystem::displacements(int freeDof) const {
  completeSolution();
  if (solution_.size() == 0) return {};
  return solution_.segment(displacementRow(freeDof, 1), dofCount_[static_cast<std::size_t>(freeDof)]);
}

}  // namespace asyncfem::detail
