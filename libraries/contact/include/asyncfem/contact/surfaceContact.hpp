// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <array>
#include <asyncfem/collision/broadPhase.hpp>
#include <asyncfem/collision/collisionSurface.hpp>
#include <asyncfem/collision/distance.hpp>
#include <asyncfem/contact/meshObstacle.hpp>
#include <asyncfem/core/vertexJacobian.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

namespace asyncfem {

/// Which surface pairs a SurfaceContact tests, and how close counts as contact.
struct SurfaceContactOptions {
  /// dhat (length, > 0): primitives closer than this repel (the contact layer's thickness).
  double thickness = 0.0;
  bool betweenBodies = true;  ///< pairs of two different objects of the mesh
  bool self = false;          ///< pairs within one object (a primitive's neighbours excluded)
  bool edges = true;          ///< edge-edge pairs besides vertex-triangle pairs
  BroadPhaseMethod broadPhase = kDefaultBroadPhase;
};

/// What the detection did so far (for run summaries); all evaluations together.
struct SurfaceContactStats {
  long long evaluations = 0;      ///< force evaluations (addForces calls)
  long long detections = 0;       ///< broad-phase runs (the other evaluations reused a candidate list)
  long long candidates = 0;       ///< candidate pairs, summed over the detections
  long long activePairs = 0;      ///< pairs closer than the thickness, summed over the evaluations
  long long largestActive = 0;    ///< the most active pairs at one evaluation
  double detectionSeconds = 0.0;  ///< broad and narrow phase over all evaluations
};

/// One primitive pair within the contact thickness: four points (ids: a mesh vertex i < n,
/// or obstacle vertex k as n + k), the closest-point weights w (first primitive's sum to
/// +1, second's to -1: a point against a triangle has (1, -b0, -b1, -b2) with b the
/// barycentric coordinates of the closest point), the unit normal N from the second
/// primitive to the first, and the signed gap s (the distance; negative for a vertex behind
/// a face of a closed surface of another body or obstacle). ds/dx_i = w_i N.
struct SurfacePair {
  std::array<int, 4> points{};
  std::array<double, 4> weights{};
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double gap = 0.0;
};

/// Penalty contact between the boundary surfaces of a mesh's objects (disconnected bodies,
/// or one body) and triangle-mesh obstacles, static or moving on a rigid path
/// (docs/collision.md, "Surface contact"). For each pair of primitives closer than the
/// thickness dhat (vertex-triangle both ways, edge-edge) the potential is
/// E = k/2 (dhat - s)^2, and the force on its points is
///     f_i = w_i (F N + f_t),  F = max(0, k (dhat - s) - c sdot),  sdot = N . sum_j w_j v_j,
/// with Coulomb friction on the tangential relative velocity t = P sum_j w_j v_j
/// (P = I - N N^T), f_t = -min(mu F, eta |t|) t / |t|: the same law as PenaltyContact's
/// against planes and spheres, per pair instead of per vertex. The weights sum to zero, so
/// the forces of a pair between two bodies sum to zero (momentum is conserved).
///
/// A vertex behind a face of a closed surface of another body or obstacle (signed gap
/// s < 0, the closest point inside the face) keeps being pushed out, up to s = -dhat;
/// within one body (self-contact) the gap is the unsigned distance, and pairs closer than
/// 2 dhat in the rest shape are left out (neighbours on a curved surface).
///
/// Candidates come from the collision library's broad phase at distance 2 dhat and are
/// reused while no surface or obstacle vertex has moved more than dhat / 2 since (a pair
/// closer than dhat is then still among them); the last 32 lists are kept (fewer for large
/// meshes: at most 32 MB of their points), for callers that visit several states in turn. Forces do not depend on
/// whether a list was reused. Thread-safe (the lists are shared under a mutex).
class SurfaceContact {
 public:
  /// mesh: the bodies (rest positions, boundary); objectOfVertex: each vertex's object
  /// (empty: one object); obstacles as given (obstacle positions at time t from their
  /// paths). Parameters k, c, mu, eta as PenaltyContactParameters. Throws ValidationError
  /// for a thickness that is not > 0 or not finite, objectOfVertex of the wrong size, or an
  /// obstacle with a bad triangle (naming the obstacle and the triangle).
  SurfaceContact(const TetMesh& mesh, std::vector<int> objectOfVertex, std::vector<MeshObstacle> obstacles,
                 SurfaceContactOptions options, double stiffness, double damping, double friction,
                 double frictionViscosity);

  /// Adds the pairs' forces at time t and state (u, v) (3n each) to forces (3n); with
  /// vertices (ascending) only their entries (their pairs read the other points' state as
  /// given).
  void addForces(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                 Eigen::VectorXd& forces, const std::vector<int>* vertices = nullptr) const;
  /// The forces of the pairs whose highest rank among their mesh vertices is owner
  /// (rank: one integer per mesh vertex), added to every mesh vertex of those pairs: the
  /// same values as addForces, so that adding every rank present gives addForces' sum. A
  /// multirate integrator gives each pair to the finest rate among its vertices this way
  /// (asyncIntegrator, "Contact between regions"). couplings, where not null: each of those
  /// pairs with F > 0 appended as addCoupledJacobian gives it (the same evaluation).
  /// Throws ValidationError for a rank list of the wrong size.
  void addForcesOfRank(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                       const std::vector<int>& rank, int owner, Eigen::VectorXd& forces,
                       VertexJacobian* couplings = nullptr) const;
  /// Appends per-vertex blocks for an implicit step: for each pair with F > 0 and each of
  /// its mesh vertices i, stiffness k |w_i| S N N^T and damping c |w_i| S N N^T with
  /// S = sum of |w_j| over the pair's mesh vertices. These block-diagonal terms bound the
  /// pair's Gauss-Newton Hessian k (w w^T) (x) N N^T from above (Gershgorin), so Newton's
  /// iteration on the exact residual converges; for a mesh vertex against an obstacle
  /// triangle they are exact. Curvature of N and friction are left out.
  void addJacobian(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                   VertexJacobian& jacobian, const std::vector<int>* vertices = nullptr) const;
  /// Appends each pair with F > 0 as one VertexCoupling (its mesh vertices, weights w, N,
  /// k and c): the pair's Gauss-Newton Hessian k (w w^T) (x) N N^T and damping
  /// c (w w^T) (x) N N^T with their off-diagonal blocks, exact but for the turning of N
  /// (a term k (dhat - s) d^2 s / dx^2, small against k where the layer is thin against
  /// the surface's edges) and friction. For integrators that can take couplings
  /// (DynamicSystem::externalForceCoupledJacobian).
  void addCoupledJacobian(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                          VertexJacobian& jacobian) const;
  /// The potential sum k/2 (dhat - s)^2 over the pairs at time t and displacement u.
  double energy(double time, const Eigen::VectorXd& displacement) const;
  /// The largest dhat - s over the pairs (0 if none).
  double maxDepth(double time, const Eigen::VectorXd& displacement) const;
  /// The pairs at time t and displacement u, in a fixed order.
  std::vector<SurfacePair> pairs(double time, const Eigen::VectorXd& displacement) const;
  /// Mesh vertices (ascending) of pairs closer than dhat + 2 margin: what may touch while
  /// every point moves by at most margin (two bodies can close up by 2 margin).
  std::vector<int> verticesWithin(double time, const Eigen::VectorXd& displacement, double margin) const;

  /// Whether some obstacle moves (the force then depends on time at a fixed state).
  bool timeDependent() const;
  /// Obstacle vertices at time t, 3 x (all obstacles' vertices, in the order given).
  Eigen::Matrix3Xd obstaclePositions(double time) const;
  const SurfaceContactOptions& options() const { return options_; }
  const CollisionSurface& bodySurface() const { return bodySurface_; }
  const CollisionSurface& obstacleSurface() const { return obstacleSurface_; }
  const std::vector<MeshObstacle>& obstacles() const { return obstacles_; }
  SurfaceContactStats stats() const;

 private:
  struct Candidates;
  /// Which candidate pairs (their four point ids) a query looks at; null: all.
  using CandidateFilter = std::function<bool(const std::array<int, 4>&)>;

  /// Where the points are: mesh vertices (rest + u) and obstacle vertices at t.
  struct Points {
    Eigen::Matrix3Xd body;
    Eigen::Matrix3Xd obstacle;
    Eigen::Matrix3Xd obstacleVelocity;  ///< empty when no obstacle moves
    Eigen::Vector3d operator()(int id) const {
      return id < body.cols() ? Eigen::Vector3d(body.col(id)) : Eigen::Vector3d(obstacle.col(id - body.cols()));
    }
  };
  Points pointsAt(double time, const Eigen::VectorXd& displacement) const;
  static Eigen::Vector3d pointVelocity(int id, const Eigen::VectorXd& velocity, const Points& points);
  std::shared_ptr<const Candidates> detect(const Points& points, double distance) const;
  std::shared_ptr<const Candidates> candidatesFor(const Points& points) const;
  /// The pairs of candidates closer than distance.
  void narrowPhase(const Candidates& candidates, const Points& points, double distance, std::vector<SurfacePair>& out,
                   const CandidateFilter* keep = nullptr) const;
  /// Whether a pair's highest mesh-vertex rank is owner (rank: one per mesh vertex, checked).
  CandidateFilter ownedBy(const std::vector<int>& rank, int owner) const;
  /// The forces of the active pairs among the candidates keep takes, added at the points
  /// wanted(id) takes.
  template <class Wanted>
  void addPairForces(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                     Eigen::VectorXd& forces, const CandidateFilter* keep, Wanted&& wanted,
                     VertexJacobian* couplings) const;
  /// A pair as a VertexCoupling (its mesh vertices, weights, normal, k and c).
  VertexCoupling couplingOf(const SurfacePair& pair) const;
  std::vector<SurfacePair> activePairs(double time, const Eigen::VectorXd& displacement, Points* points,
                                       const CandidateFilter* keep = nullptr) const;
  /// Whether a vertex-triangle pair is its contact's one pair: when its closest point is an
  /// edge or corner of the triangle (to round-off), no other triangle through that feature is
  /// closer, it is the first of equally close ones, and two points count once.
  bool countsOnce(const SurfacePair& pair, int triangle, double squaredDistance, const Points& points) const;

  Eigen::Matrix3Xd rest_;
  std::vector<int> objectOfVertex_;
  std::vector<MeshObstacle> obstacles_;
  std::vector<int> obstacleOfVertex_;         // per obstacle vertex: its obstacle
  std::vector<char> obstacleTriangleSigned_;  // per obstacle triangle: its obstacle is closed
  CollisionSurface bodySurface_;
  CollisionSurface obstacleSurface_;
  Eigen::Matrix3Xi allTriangles_;                   // body triangles, then obstacle triangles (point ids)
  std::vector<std::vector<int>> trianglesOfPoint_;  // per point id: the triangles using it
  SurfaceContactOptions options_;
  double stiffness_, damping_, friction_, frictionViscosity_;

  mutable std::mutex mutex_;
  static constexpr std::size_t kKeptLists = 32;
  static constexpr std::size_t kKeptPointValues = 4000000;
  mutable std::vector<std::shared_ptr<const Candidates>> cached_;  // most recently used first
  mutable SurfaceContactStats stats_;
};

}  // namespace asyncfem
