// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/core/vertexJacobian.hpp>
#include <memory>
#include <vector>

namespace asyncfem {

/// A static half-space obstacle {x : n . x >= offset}; the body must stay on the side n
/// points to. The ground is a plane with n = up.
struct ContactPlane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();  ///< normalised by the model
  double offset = 0.0;                                ///< n . x on the plane
};

/// A static solid sphere obstacle.
struct ContactSphere {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 1.0;
};

/// Penalty contact of the mesh vertices against static planes and spheres.
///
/// For a vertex at x = X + u with velocity v and penetration depth d > 0 along the
/// obstacle's outward normal n (plane: d = offset - n . x; sphere: d = r - |x - c|,
/// n = (x - c)/|x - c|), the force is
///     f_n = (k d - c (v . n)) n, clamped so that its normal component is >= 0
///           (the obstacle pushes, never pulls),
/// and with Coulomb friction (mu > 0) a tangential force opposing the tangential
/// velocity v_t,
///     f_t = -min(mu |f_n|, eta |v_t|) v_t / |v_t|,
/// regularised by eta (viscous below the sliding threshold, so resting contact does not
/// chatter). k: stiffness (force / length per vertex), c: normal damping (force /
/// velocity per vertex). Frictionless when mu = 0 (default).
///
/// The forces are evaluated at one state; integrators apply them explicitly, or (single-rate
/// backward Euler with DynamicSystem::externalForceJacobian) linearized with jacobian().
struct PenaltyContactParameters {
  double stiffness = 1e4;
  double damping = 0.0;
  double friction = 0.0;           ///< Coulomb coefficient mu
  double frictionViscosity = 1e3;  ///< eta
};

/// The derivatives of PenaltyContact's forces at one state, per vertex in contact
/// (stiffness = -df/du, damping = -df/dv; a vertex touching two obstacles appears twice):
/// what an implicit integrator adds to its system matrix to treat contact implicitly
/// (linearized at that state).
using PenaltyContactJacobian = VertexJacobian;

class SurfaceContact;

class PenaltyContact {
 public:
  /// restPositions: 3 x n. Throws asyncfem::ValidationError for a non-positive stiffness,
  /// negative damping/friction, a zero plane normal or a non-positive sphere radius.
  /// surfaces: contact between the mesh's boundary surfaces and triangle-mesh obstacles
  /// (SurfaceContact), added to every query below; null: planes and spheres only.
  PenaltyContact(Eigen::Matrix3Xd restPositions, std::vector<ContactPlane> planes, std::vector<ContactSphere> spheres,
                 PenaltyContactParameters parameters, std::shared_ptr<const SurfaceContact> surfaces = nullptr);

  /// The queries below at time t: moving obstacles (SurfaceContact) are where their paths
  /// put them then; the overloads without a time evaluate at t = 0.
  void addForces(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                 Eigen::VectorXd& forces, const std::vector<int>* vertices = nullptr) const;
  PenaltyContactJacobian jacobian(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                                  const std::vector<int>* vertices = nullptr) const;
  /// The planes' and spheres' forces at the listed vertices (ascending) and the surface
  /// pairs of rank owner (SurfaceContact::addForcesOfRank) on all their vertices: the
  /// terms a multirate integrator evaluates at the states of the rate with that rank.
  /// jacobian, where not null: their derivatives from the same evaluation, jacobian()'s
  /// blocks of the planes and spheres at the listed vertices and the pairs as couplings.
  void addForcesOfRank(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                       const std::vector<int>& vertices, const std::vector<int>& rank, int owner,
                       Eigen::VectorXd& forces, PenaltyContactJacobian* jacobian = nullptr) const;
  /// jacobian() with the surface contact's pairs as couplings (SurfaceContact::addCoupledJacobian)
  /// instead of per-vertex bounds; the planes' and spheres' blocks as jacobian() gives them.
  PenaltyContactJacobian coupledJacobian(double time, const Eigen::VectorXd& displacement,
                                         const Eigen::VectorXd& velocity) const;
  double energy(double time, const Eigen::VectorXd& displacement) const;
  /// Whether the force at a fixed state changes with time (a moving obstacle).
  bool timeDependent() const;
  /// The surface contact, or null.
  const std::shared_ptr<const SurfaceContact>& surfaces() const { return surfaces_; }

  /// Adds the contact forces at state (u, v) (both 3n) to forces (3n). Only vertices in
  /// `vertices` are tested when it is non-null (e.g. a fast region's vertices).
  void addForces(const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity, Eigen::VectorXd& forces,
                 const std::vector<int>* vertices = nullptr) const;

  /// The derivatives of addForces' forces at (u, v) (same vertex filter), exact where the
  /// force is smooth: a plane's normal force gives k n n^T and c n n^T; a sphere's adds the
  /// turning of its normal, (k d - c v.n) (I - n n^T) / |x - c| and the damping's term;
  /// friction adds eta P (viscous regime, P = I - n n^T) or the derivatives of
  /// mu f_n t / |t| (sliding). Where the normal force is clamped to zero the vertex has no
  /// entry; at the kinks (f_n = 0, mu f_n = eta |t|, t = 0) the one-sided derivative of the
  /// branch addForces takes.
  PenaltyContactJacobian jacobian(const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                                  const std::vector<int>* vertices = nullptr) const;

  /// The penalty potential at u, k/2 times the sum of d^2 over the vertices in contact and
  /// their obstacles: the normal spring's force is minus its gradient, so with it the
  /// contact forces do no net work (damping, the clamp and friction only dissipate).
  double energy(const Eigen::VectorXd& displacement) const;
  /// Largest penetration depth over all vertices and obstacles at u (0 if none): below the
  /// planes and spheres, and into the surfaces' contact layer (SurfaceContact::maxDepth,
  /// moving obstacles where they are at t; the overload without a time at t = 0).
  double maxPenetration(double time, const Eigen::VectorXd& displacement) const;
  double maxPenetration(const Eigen::VectorXd& displacement) const;
  /// Number of vertices in contact at u.
  int activeContacts(const Eigen::VectorXd& displacement) const;
  /// Vertices (ascending) in contact at u or closer than margin (length, >= 0) to an
  /// obstacle: what a contact-following fast region needs.
  std::vector<int> verticesWithin(const Eigen::VectorXd& displacement, double margin) const;

  const PenaltyContactParameters& parameters() const { return parameters_; }

 private:
  /// addForces' planes and spheres (no surface contact).
  void addPrimitiveForces(const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity, Eigen::VectorXd& forces,
                          const std::vector<int>* vertices) const;
  /// jacobian()'s blocks of the planes and spheres (no surface contact).
  PenaltyContactJacobian primitiveJacobian(const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                                           const std::vector<int>* vertices) const;
  template <class Visitor>
  /// visit(vertex, depth, normal, curvature) for every vertex and obstacle with depth >
  /// -margin (margin 0: the vertices in contact), vertices in ascending order; curvature is
  /// 1 / |x - c| for a sphere (how fast its normal turns with x), 0 for a plane.
  void forEachContact(const Eigen::VectorXd& displacement, const std::vector<int>* vertices, Visitor&& visit,
                      double margin = 0.0) const;

  Eigen::Matrix3Xd restPositions_;
  std::vector<ContactPlane> planes_;
  std::vector<ContactSphere> spheres_;
  PenaltyContactParameters parameters_;
  std::shared_ptr<const SurfaceContact> surfaces_;
};

}  // namespace asyncfem
