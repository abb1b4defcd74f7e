// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/core/vertexJacobian.hpp>
#include <asyncfem/forceModel/forceModel.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <functional>
#include <memory>
#include <vector>

namespace asyncfem {

/// External force as a function of time and state: adds its contribution to forces
/// (size 3n, zeroed by the caller). The state arguments let explicit force terms
/// (penalty contact, springs) depend on it; time-only loads ignore them.
using ExternalForceFunction = std::function<void(double time, const Eigen::VectorXd& displacement,
                                                 const Eigen::VectorXd& velocity, Eigen::VectorXd& forces)>;

/// Whether the external force at a fixed state may differ, at some time in (from, to], from
/// its value at `to`. false lets a multirate integrator evaluate it once for all its
/// substeps in that interval instead of once per substep time; true is always a correct
/// answer (it only costs those evaluations).
using ExternalForceChanges = std::function<bool(double from, double to)>;

/// The derivatives of the external force's state-dependent part at time and state (u, v),
/// per vertex (stiffness = -df/du, damping = -df/dv), into jacobian (cleared first): what an
/// implicit integrator needs to treat that part implicitly (penalty contact).
using ExternalForceJacobianFunction = std::function<void(double time, const Eigen::VectorXd& displacement,
                                                         const Eigen::VectorXd& velocity, VertexJacobian& jacobian)>;

/// externalForce at some vertices only: adds the listed vertices' (ascending) entries of
/// f_ext(t, u, v) to forces, the same values in the same order of additions as
/// externalForce, and leaves every other entry as it is. It may read the state of the
/// listed vertices only (the caller may leave the others' entries at another time's state):
/// per-vertex loads and penalty contact are such forces.
using ExternalForceAtFunction =
    std::function<void(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                       const std::vector<int>& vertices, Eigen::VectorXd& forces)>;

/// The terms of the external force that belong to one rank: given a rank per mesh vertex
/// (rank, size n), a term belongs to the highest rank among the mesh vertices it acts on. Adds
/// to forces the terms of rank owner: the per-vertex ones (loads, obstacle contact) at the
/// listed vertices (ascending; the caller lists those of that rank), and every term that
/// joins several mesh vertices (a surface contact pair between bodies or within one) on all
/// of its vertices, whatever their ranks. Summed over the ranks present (each with its
/// vertices), it is externalForce. What lets a multirate integrator evaluate a pair at the
/// states of its finest vertex and give its slower vertices the matching impulse.
/// jacobian, where not null and the system has externalForceJacobian: the derivatives of
/// those terms from the same evaluation (cleared first): the per-vertex terms' as per-vertex
/// blocks, those that join vertices as VertexJacobian::couplings.
using ExternalForceOfRankFunction = std::function<void(
    double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity, const std::vector<int>& vertices,
    const std::vector<int>& rank, int owner, Eigen::VectorXd& forces, VertexJacobian* jacobian)>;

/// externalForceJacobian at some vertices only: the entries of the listed vertices
/// (ascending), in the order externalForceJacobian gives them.
using ExternalForceJacobianAtFunction =
    std::function<void(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                       const std::vector<int>& vertices, VertexJacobian& jacobian)>;

/// The vertices (ascending) closer than margin (a length) to an obstacle of the external
/// force at displacement u, into vertices: what lets an integrator follow contact.
using ObstacleProximity =
    std::function<void(const Eigen::VectorXd& displacement, double margin, std::vector<int>& vertices)>;

/// The body an integrator advances: M a + D v + f_int(u) = f_ext(t), with
/// D = alpha M + beta K (K the tangent stiffness at the start of a step) and the DOFs in
/// freeDofs' fixed list held at zero displacement and velocity. What it is, not how it is
/// stepped: the steppers (library integrator and above) take it by value.
struct DynamicSystem {
  std::shared_ptr<ForceModel> forceModel;
  Eigen::SparseMatrix<double> mass;  ///< 3n x 3n, in the force model's stiffness pattern
  FreeDofs freeDofs;
  double rayleighMass = 0.0;            ///< alpha (1/s)
  double rayleighStiffness = 0.0;       ///< beta (s)
  ExternalForceFunction externalForce;  ///< may be empty: no external force
  /// When externalForce changes in time (Problem sets it from its loads' windows). Empty:
  /// it may change at any time (a user's force function). Whoever replaces externalForce
  /// must reset or replace this too.
  ExternalForceChanges externalForceChanges;
  /// When set, the external force is to be treated implicitly: integrators that can
  /// (Integrator::linearizesExternalForce(): single-rate BackwardEuler) use these
  /// derivatives; the others apply the force explicitly as always, and
  /// IntegratorRegistry::create refuses to build them for such a system.
  /// Whoever replaces externalForce must reset or replace this too.
  ExternalForceJacobianFunction externalForceJacobian;
  /// Optional: the same derivatives with the terms that couple vertices kept as
  /// VertexJacobian::couplings (surface contact pairs' k (w w^T) (x) N N^T) instead of
  /// externalForceJacobian's per-vertex bounds of them. Single-rate backward Euler on a
  /// linear force model uses it where set (its Newton iteration then converges
  /// quadratically where the bounds made it linear); the other integrators use
  /// externalForceJacobian. Ignored without externalForceJacobian (clearing that turns
  /// implicit treatment off for every integrator, as before this field existed).
  ExternalForceJacobianFunction externalForceCoupledJacobian;
  /// Optional shortcuts of externalForce and externalForceJacobian for a few vertices at a
  /// time: an integrator that needs some vertices' force at many states (the asynchronous
  /// one's fast substeps, at their predicted states or in its implicit contact iteration)
  /// calls them where set, else the whole-body functions, with the same result. Whoever replaces externalForce or
  /// externalForceJacobian must reset or replace these too.
  ExternalForceAtFunction externalForceAt;
  ExternalForceJacobianAtFunction externalForceJacobianAt;
  /// Optional: set where the external force has terms that join several mesh vertices
  /// (surface contact). The asynchronous integrator then evaluates each such term at the
  /// states of the finest rate among its vertices (docs/asynchronous-integrator.md,
  /// "Contact between regions"); without it every vertex's force is taken at its own
  /// rate's states, which is exact only for per-vertex terms. Whoever replaces externalForce
  /// must reset or replace this too.
  ExternalForceOfRankFunction externalForceOfRank;
  /// Where the external force's obstacles are (penalty contact); empty without obstacles.
  ObstacleProximity obstacleProximity;
  /// true when externalForce depends on the state (u, v) only at vertices in contact with
  /// an obstacle of obstacleProximity (a vertex it does not list at some margin has no
  /// state-dependent force while it stays within that distance of where it is), and on
  /// time alone everywhere else: what a Problem's loads are (gravity, windows, penalty
  /// contact). It lets the asynchronous integrator certify a step free of contact from
  /// bounds on its motion instead of every substep's state. false (default) is always
  /// correct. Whoever replaces externalForce or obstacleProximity must reset this too.
  bool stateDependentOnlyInContact = false;
  /// The mesh the matrices were built from (n vertices). Integrators that partition the
  /// body by vertices or elements (the multirate ones) need it; single-rate ones do not,
  /// so it may be null for a system built from matrices alone.
  std::shared_ptr<const TetMesh> mesh;

  int numDofs() const { return static_cast<int>(mass.rows()); }
  bool damped() const { return rayleighMass != 0.0 || rayleighStiffness != 0.0; }
  /// Throws asyncfem::ValidationError if sizes disagree (the mesh's too, when there is
  /// one) or alpha, beta < 0.
  void validate() const;
};

}  // namespace asyncfem
