// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/integrator/multirateIntegrator.hpp>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace asyncfem {

/// The step counts of a hierarchy of fast regions: each vertex's number of steps per
/// large step (docs/asynchronous-integrator.md, "Nested and touching regions").
///
/// Regions are given as for AsyncBackwardEuler, except that they may touch one another
/// and nest: region i takes ratio_i steps per large step (its count, relative to L, so a
/// region of ratio 32 beside one of ratio 8 is "4 inside 8"). What the coupling needs is
/// checked per element: the counts of an element's vertices must each divide the largest
/// of them (Eq. N6). Rejected with asyncfem::ValidationError naming the culprit: a ratio <
/// 1, a vertex in two regions, a vertex id out of range, a region with no free DOF, an
/// element whose counts do not divide one another (names the element, its regions and
/// their ratios), and counts whose least common multiple exceeds 2^20.
class StepCounts {
 public:
  StepCounts(const TetMesh& mesh, const FreeDofs& freeDofs, std::vector<AsyncRegion> regions);

  int numRegions() const { return static_cast<int>(regions_.size()); }
  const AsyncRegion& region(int i) const { return regions_[static_cast<std::size_t>(i)]; }
  /// Steps per large step of every vertex (1 in L).
  const std::vector<int>& vertexCounts() const { return vertexCounts_; }
  /// Region of every vertex (-1: L).
  const std::vector<int>& vertexRegion() const { return vertexRegion_; }
  /// Steps per large step of every element: its fastest vertex's count.
  const std::vector<int>& elementCounts() const { return elementCounts_; }
  /// Least common multiple of every count: the large step in time units.
  long long units() const { return units_; }
  /// The distinct counts, ascending (1 first when L has a vertex).
  const std::vector<int>& levels() const { return levels_; }
  /// Whether an element has vertices in two different fast regions (touching regions).
  bool touching() const { return touching_; }

 private:
  void assignVertices(const TetMesh& mesh, const FreeDofs& freeDofs);
  void checkElements(const TetMesh& mesh);
  std::vector<AsyncRegion> regions_;
  std::vector<int> vertexCounts_, vertexRegion_, elementCounts_, levels_;
  long long units_ = 1;
  bool touching_ = false;
};

/// How NestedAsyncBackwardEuler solves its step system (docs/asynchronous-integrator.md,
/// "The solve").
enum class NestedSolve {
  /// structured when the step counts form a chain (each divides the next, e.g. 1, 8, 32),
  /// the LU otherwise
  automatic,
  /// level by level, one factor per level (Eqs. N9-N12); asyncfem::ValidationError when the
  /// counts do not form a chain
  structured,
  /// one sparse LU of the whole step system (Eq. N8), for any counts N6 allows
  lu,
};
/// "automatic", "structured", "lu".
std::string toString(NestedSolve solve);
/// Inverse of toString; throws asyncfem::ValidationError naming the valid values.
NestedSolve parseNestedSolve(const std::string& name);

namespace detail {
class HierarchySystem;
}

/// Asynchronous backward Euler with nested and touching fast regions, under the stable
/// coupling's rules generalized to any number of levels (docs/asynchronous-integrator.md,
/// "Nested and touching regions", Eqs. N1-N6 and Theorem N): every vertex moves at its
/// own step's end velocity, every element is evaluated on its fastest vertex's steps and
/// credits each impulse to the step it falls in. A free, undamped linear system never
/// gains energy, whatever the hierarchy.
///
/// Solve: the per-step equations are written with the velocity and the displacement of
/// every DOF at the end of each of its steps as unknowns (Eq. N5), which keeps every
/// coupling local in time. When the step counts divide one another in a chain (1, 8, 32)
/// it is solved level by level (Eqs. N9-N12: one Schur complement and factor per level, the
/// cost of AsyncBackwardEuler's structured solve per level); otherwise, or on request
/// (NestedSolve::lu), by one sparse LU of the whole system. Linear force models factor once
/// per hL; nonlinear ones linearize at the start of each large step (f_int(u_0), element
/// tangents K_e(u_0)) and refactor numerically, as AsyncBackwardEuler does. With two
/// levels its steps equal AsyncBackwardEuler's stable coupling to round-off.
///
/// Rayleigh damping is an element force: D_e = alpha M_e + beta K_e, with M_e the mesh's
/// consistent or lumped element mass, whichever sums to the system's mass (checked;
/// neither with alpha > 0 throws asyncfem::ValidationError). Linear models without
/// element tangents must equal the mesh's linear FEM stiffness (checked, relative 1e-10).
class NestedAsyncBackwardEuler final : public Integrator, public MultirateIntegrator {
 public:
  /// system.mesh must be set. Throws asyncfem::ValidationError for what StepCounts
  /// rejects, a system without a mesh, or the checks above.
  NestedAsyncBackwardEuler(DynamicSystem system, double largeTimestep, std::vector<AsyncRegion> regions,
                           NestedSolve solve = NestedSolve::automatic);
  ~NestedAsyncBackwardEuler() override;

  std::string name() const override { return "async"; }
  void step() override;
  void setTimestep(double timestep) override;
  RunReport report() const override;
  const MultirateIntegrator* multirate() const override { return this; }
  std::vector<RegionSummary> regionSummaries() const override;
  int regionOfVertex(int vertex) const override;

  const StepCounts& counts() const { return counts_; }
  /// Unknowns of the step system (2 sum over free DOFs of their counts).
  long long unknowns() const;
  /// Entries the solve keeps: the LU's factor, or the structured solve's per-level factors
  /// and dense recovery blocks.
  long long factorNonZeros() const;
  /// Whether the structured solve is in use (after the first step: it falls back to the LU
  /// under NestedSolve::automatic when its check fails, see report()).
  bool structuredSolve() const;
  /// The last step's velocities v_{d,j} and displacement changes u_{d,j} - u_{d,0} of free
  /// DOF d (index into system().freeDofs.freeToFull()) at the end of its steps j = 1..N_d,
  /// in order (empty before the first step). For checks against the step's definition.
  Eigen::VectorXd stepVelocities(int freeDof) const;
  Eigen::VectorXd stepDisplacements(int freeDof) const;

 private:
  void rebuild();
  StepCounts counts_;
  std::unique_ptr<detail::HierarchySystem> hierarchy_;
  std::vector<RegionSummary> summaries_;
  // Per-step buffers: f_int(u_0), f_ext at each step-end time unit, the new state.
  Eigen::VectorXd internalForce_, newDisplacement_, newVelocity_;
  std::map<long long, Eigen::VectorXd> external_;
  bool linear_ = true;
  bool built_ = false;
  double setUpSeconds_ = 0.0;
};

}  // namespace asyncfem
