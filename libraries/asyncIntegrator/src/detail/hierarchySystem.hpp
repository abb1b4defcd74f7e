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
#include <asyncfem/core/vertexJacobian.hpp>
#include <asyncfem/dynamics/dynamicSystem.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "detail/elementTangents.hpp"

namespace asyncfem::detail {

class StructuredHierarchySolve;

/// The step of a DOF with `unitsPerStep` units per step that time unit t > 0 falls in:
/// steps are (t_{j-1}, t_j], so ceil(t / unitsPerStep); 0 for t = 0 (the start state).
inline long long stepContaining(long long t, long long unitsPerStep) { return (t + unitsPerStep - 1) / unitsPerStep; }

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
  /// A force that depends on the state (implicit penalty contact): f_ext at a time and a
  /// full state (into a zeroed vector), its vertex Jacobian there (stiffness = -df/du,
  /// damping = -df/dv), and the time of a time unit of the step.
  struct StateForce {
    std::function<void(double time, const Eigen::VectorXd& u, const Eigen::VectorXd& v, Eigen::VectorXd& f)> force;
    std::function<void(double time, const Eigen::VectorXd& u, const Eigen::VectorXd& v, VertexJacobian& jacobian)>
        jacobian;
    std::function<double(long long unit)> timeOf;
  };
  /// How solveWithStateForce ended: solves (the first one, step()'s, included), the largest
  /// residual relative to the step's scale, and the free DOF where it is largest.
  struct StateForceSolve {
    int solves = 1;
    double residual = 0.0;
    bool converged = false;
    int worstDof = -1;       ///< a full DOF index, -1 if none
    int factorizations = 0;  ///< LU factorizations of the step system with contact blocks
  };
  /// After step() (its solution the first iterate): Newton's method on the step equations
  /// with f_ext on each DOF's step evaluated at that DOF's own state at the step's end (Eq.
  /// N13), the Jacobian's blocks added to the step system of the iterate (one sparse LU of
  /// it, Eq. N14), each update halved while the residual's 2-norm would rise, until the
  /// largest residual is at most tolerance relative to the step's scale or maxSolves solves
  /// are spent. Writes the end state into u1, v1.
  StateForceSolve solveWithStateForce(const Eigen::VectorXd& u0, const Eigen::VectorXd& v0,
                                      const Eigen::VectorXd& internalForce, const StateForce& force, double tolerance,
                                      int maxSolves, Eigen::VectorXd& u1, Eigen::VectorXd& v1, IntegratorStats& stats);
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
  Eigen::MatrixXd elementMass(int e) const;
  /// The elimination order (Eq. N8): unknowns by the time their step ends, then by an AMD
  /// order of the free DOFs' graph, v before w; and the row scaling of the position rows.
  void chooseOrder();
  void factorize(IntegratorStats& stats);
  void factorizeLU(IntegratorStats& stats);
  /// The end of the step solved last (each DOF's last step; fixed DOFs at u0, v0).
  void endState(const Eigen::VectorXd& u0, const Eigen::VectorXd& v0, Eigen::VectorXd& u1, Eigen::VectorXd& v1) const;
  /// Completes solution_ (every step's unknowns) after a structured solve.
  void completeSolution() const;
  /// Eq. N3's right-hand side into rhs: h_d (f_ext,d(t_{d,j}) - f_int,d(u_0)), plus
  /// (M v_0)_d in d's first step; external maps time units to f_ext (absent: zero).
  void loadRightHandSide(const Eigen::VectorXd& v0, const Eigen::VectorXd& internalForce,
                         const std::map<long long, Eigen::VectorXd>& external, Eigen::VectorXd& rhs) const;
  /// The full state at time unit t of the step whose unknowns are x (Eq. N1; fixed DOFs
  /// at u0, v0).
  void stateAt(long long t, const Eigen::VectorXd& x, const Eigen::VectorXd& u0, const Eigen::VectorXd& v0,
               Eigen::VectorXd& u, Eigen::VectorXd& v) const;
  /// f_ext at every step end, each at the state of x (Eq. N13).
  void forcesAt(const Eigen::VectorXd& x, const Eigen::VectorXd& u0, const Eigen::VectorXd& v0, const StateForce& force,
                std::map<long long, Eigen::VectorXd>& out) const;
  /// The largest entry of |matrix_ x - rhs| (its DOF into worstDof) and its 2-norm.
  double residualOf(const Eigen::VectorXd& x, const Eigen::VectorXd& rhs, double& norm, int& worstDof) const;
  /// Solves the step system plus blocks (triplets; none: with the kept factor).
  void solveWith(const std::vector<Eigen::Triplet<double>>& blocks, const Eigen::VectorXd& rhs, Eigen::VectorXd& x,
                 IntegratorStats& stats);
  /// Row scales of the position rows (Eq. N5), for an LU of the step system.
  void scalePositionRows();

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
  // Implicit contact: the LU of the step system with the Jacobian's blocks (Eq. N14).
  Eigen::SparseLU<SparseMatrix, Eigen::NaturalOrdering<int>> contactLu_;
};

}  // namespace asyncfem::detail
