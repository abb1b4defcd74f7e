// SPDX-License-Identifier: BSD-3-Clause
// The step system of nested and touching fast regions (docs/asynchronous-integrator.md,
// "Nested and touching regions", Eqs. N1-N6): unknowns, assembly, factor and solve.
// Private to the library.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>
#include <asyncfem/asyncIntegrator/asyncOptions.hpp>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/dynamics/dynamicSystem.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "detail/elementTangents.hpp"

namespace asyncfem::detail {

class StructuredHierarchySolve;

/// Free DOF d (index into freeToFull) takes N_d steps of h_d = hL / N_d per large step; its
/// unknowns are v_{d,j} (rows and columns offset_[d] + j - 1) and w_{d,j} = u_{d,j} - u_{d,0}
/// (the same plus unknowns() / 2), j = 1..N_d. Time is counted in units of hL / units().
class HierarchySystem {
 public:
  using SparseMatrix = Eigen::SparseMatrix<double>;

  /// Checks the element tangents and masses the system needs (AsyncBackwardEuler, "The
  /// hierarchy solve") and lays out the unknowns of partition's step counts (copied).
  /// Throws asyncfem::ValidationError when the counts' least common multiple exceeds
  /// RegionPartition::kMaxUnits, the system is too large, or a check fails.
  HierarchySystem(const TetMesh& mesh, const DynamicSystem& system, const RegionPartition& partition,
                  NestedSolve solve);
  ~HierarchySystem();

  /// Element tangents at u (the linear ones when the model has none), summed per element
  /// count, the matrix of Eqs. N4-N5 for large step hL, and its factor (symbolic analysis
  /// once). Adds to stats.
  void build(const Eigen::VectorXd& u, double largeStep, IntegratorStats& stats);
  /// One large step from (u0, v0) with f_int(u0) = internalForce (full vectors): external
  /// maps each time unit at which some DOF's step ends to f_ext there (full). Writes the
  /// end state (full; fixed entries untouched) into u1, v1.
  void step(const Eigen::VectorXd& u0, const Eigen::VectorXd& v0, const Eigen::VectorXd& internalForce,
            const std::map<long long, Eigen::VectorXd>& external, Eigen::VectorXd& u1, Eigen::VectorXd& v1,
            IntegratorStats& stats);
  /// Time units at which some free DOF's step ends (where f_ext is needed), ascending.
  const std::vector<long long>& stepEndUnits() const { return stepEndUnits_; }

  long long unknowns() const { return 2LL * velocityUnknowns_; }
  long long factorNonZeros() const { return factorNonZeros_; }
  bool structured() const { return structured_ != nullptr; }
  /// How the system is solved, for the run report.
  std::string solveDescription() const;
  /// v_{d,1..N_d} and w_{d,1..N_d} of free DOF d from the last step.
  Eigen::VectorXd velocities(int freeDof) const;
  Eigen::VectorXd displacements(int freeDof) const;

 private:
  /// Which element mass sums to the system's mass (for D_e = alpha M_e + beta K_e).
  enum class ElementMass { none, consistent, lumped };
  void chooseElementMass();
  void checkLinearStiffness();
  void groupElements(const Eigen::VectorXd& u);
  void addPositionRows(std::vector<Eigen::Triplet<double>>& out) const;
  void addMassRows(std::vector<Eigen::Triplet<double>>& out) const;
  /// The impulses of the elements with count `count`: matrix K_g (displacement term,
  /// Eq. N2) or D_g (velocity term), credited to the rows of the steps they fall in.
  void addElementRows(int count, const SparseMatrix& matrix, bool displacementTerm,
                      std::vector<Eigen::Triplet<double>>& out) const;
  Eigen::Matrix<double, 12, 12> elementMass(int e) const;
  /// The elimination order (Eq. N8): unknowns by the time their step ends, then by an AMD
  /// order of the free DOFs' graph, v before w; and the row scaling of the position rows.
  void chooseOrder();
  void factorize(IntegratorStats& stats);
  void factorizeLU(IntegratorStats& stats);
  /// Completes solution_ (every step's unknowns) after a structured solve.
  void completeSolution() const;

  int velocityRow(int d, long long j) const { return offset_[static_cast<std::size_t>(d)] + static_cast<int>(j) - 1; }
  int displacementRow(int d, long long j) const { return velocityUnknowns_ + velocityRow(d, j); }
  long long unitsPerStep(int d) const { return units_ / dofCount_[static_cast<std::size_t>(d)]; }

  const TetMesh& mesh_;
  const DynamicSystem& system_;
  ElementTangents tangents_;
  std::vector<int> elementCounts_;
  std::vector<int> free_, freeIndex_, dofCount_, offset_;
  std::vector<long long> stepEndUnits_;
  int velocityUnknowns_ = 0;
  long long units_ = 1;
  double largeStep_ = 0.0;
  ElementMass elementMass_ = ElementMass::none;
  std::map<int, SparseMatrix> stiffnessByCount_, massByCount_;  // K_g, M_g per element count g
  SparseMatrix matrix_;
  // The factor of P S A P^T (S scales the position rows, P the order of chooseOrder()),
  // by supernodal LU in that order: a fill-reducing order made for this system keeps the
  // factor near the structured solve's size, where a general ordering does not.
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> order_;
  Eigen::VectorXd rowScale_;
  Eigen::SparseLU<SparseMatrix, Eigen::NaturalOrdering<int>> lu_;
  bool analyzed_ = false;
  long long factorNonZeros_ = 0;
  Eigen::VectorXd rhs_;
  mutable Eigen::VectorXd solution_;
  mutable bool solutionComplete_ = false;
  // Eqs. N9-N12 when the counts form a chain (NestedSolve); null: the LU above.
  NestedSolve requested_ = NestedSolve::automatic;
  std::unique_ptr<StructuredHierarchySolve> structured_;
  bool structureChecked_ = false;
  std::string fallbackReason_;
};

}  // namespace asyncfem::detail
