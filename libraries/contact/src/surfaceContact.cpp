// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/collision/distance.hpp>
#include <asyncfem/contact/surfaceContact.hpp>
#include <asyncfem/core/error.hpp>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <string>

namespace asyncfem {

/// Candidate pairs in point ids (see SurfacePair), filtered by the options and the rest
/// shape but not by distance, with the positions they were found at.
struct SurfaceContact::Candidates {
  Eigen::Matrix3Xd body;
  Eigen::Matrix3Xd obstacle;
  std::vector<std::array<int, 4>> pointTriangle;  // (p, a, b, c)
  std::vector<char> pointTriangleSigned;          // the triangle is another closed surface's
  std::vector<int> pointTriangleIndex;            // the triangle in allTriangles_
  std::vector<std::array<int, 4>> edgeEdge;       // (a0, a1, b0, b1)
};

namespace {

using Clock = std::chrono::steady_clock;

// A pair's weights and normal from the gradient of its squared distance q = d^2:
// dq/dx_i = 2 d w_i N, so g_i = dq/dx_i / (2 d) = w_i N, N = g of the first primitive
// (whose weights sum to one), w_i = g_i . N.
SurfacePair pairFromGradient(const std::array<int, 4>& points, const SquaredDistance& distance, int firstPoints,
                             double sign) {
  SurfacePair pair;
  pair.points = points;
  const double d = std::sqrt(distance.value);
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  for (int i = 0; i < firstPoints; ++i) normal += distance.gradient.segment<3>(3 * i) / (2.0 * d);
  for (int i = 0; i < 4; ++i)
    pair.weights[static_cast<std::size_t>(i)] = distance.gradient.segment<3>(3 * i).dot(normal) / (2.0 * d);
  pair.normal = sign * normal;
  pair.gap = sign * d;
  return pair;
}

}  // namespace

SurfaceContact::SurfaceContact(const TetMesh& mesh, std::vector<int> objectOfVertex,
                               std::vector<MeshObstacle> obstacles, SurfaceContactOptions options, double stiffness,
                               double damping, double friction, double frictionViscosity)
    : rest_(mesh.restPositions()),
      objectOfVertex_(std::move(objectOfVertex)),
      obstacles_(std::move(obstacles)),
      options_(options),
      stiffness_(stiffness),
      damping_(damping),
      friction_(friction),
      frictionViscosity_(frictionViscosity) {
  if (!(options_.thickness > 0.0) || !std::isfinite(options_.thickness)) {
    throw ValidationError("surface contact: the thickness must be a finite length > 0");
  }
  if (objectOfVertex_.empty()) objectOfVertex_.assign(static_cast<std::size_t>(mesh.numVertices()), 0);
  if (static_cast<int>(objectOfVertex_.size()) != mesh.numVertices()) {
    throw ValidationError("surface contact: objectOfVertex has " + std::to_string(objectOfVertex_.size()) +
                          " entries for " + std::to_string(mesh.numVertices()) + " vertices");
  }
  bodySurface_ = boundarySurface(mesh);
  int vertexCount = 0;
  int triangleCount = 0;
  for (const MeshObstacle& obstacle : obstacles_) {
    vertexCount += static_cast<int>(obstacle.vertices.cols());
    triangleCount += static_cast<int>(obstacle.triangles.cols());
  }
  Eigen::Matrix3Xi triangles(3, triangleCount);
  int vertexOffset = 0;
  int triangleOffset = 0;
  for (std::size_t o = 0; o < obstacles_.size(); ++o) {
    const MeshObstacle& obstacle = obstacles_[o];
    const int m = static_cast<int>(obstacle.vertices.cols());
    try {
      (void)triangleSurface(obstacle.triangles, m);  // ids in range, no repeated corner
    } catch (const Error& error) {
      throw ValidationError("obstacle '" + obstacle.name + "': " + error.what());
    }
    if (!obstacle.vertices.allFinite()) {
      throw ValidationError("obstacle '" + obstacle.name + "': a vertex is not finite");
    }
    triangles.middleCols(triangleOffset, obstacle.triangles.cols()) = obstacle.triangles.array() + vertexOffset;
    obstacleOfVertex_.insert(obstacleOfVertex_.end(), static_cast<std::size_t>(m), static_cast<int>(o));
    obstacleTriangleSigned_.insert(obstacleTriangleSigned_.end(), static_cast<std::size_t>(obstacle.triangles.cols()),
                                   obstacle.closed ? 1 : 0);
    vertexOffset += m;
    triangleOffset += static_cast<int>(obstacle.triangles.cols());
  }
  obstacleSurface_ = triangleSurface(triangles, vertexCount);
  const int n = mesh.numVertices();
  allTriangles_.resize(3, bodySurface_.numTriangles() + obstacleSurface_.numTriangles());
  allTriangles_.leftCols(bodySurface_.numTriangles()) = bodySurface_.triangles;
  allTriangles_.rightCols(obstacleSurface_.numTriangles()) = obstacleSurface_.triangles.array() + n;
  trianglesOfPoint_.resize(static_cast<std::size_t>(n + vertexCount));
  for (int t = 0; t < allTriangles_.cols(); ++t)
    for (int c = 0; c < 3; ++c) trianglesOfPoint_[static_cast<std::size_t>(allTriangles_(c, t))].push_back(t);
}

bool SurfaceContact::countsOnce(const SurfacePair& pair, int triangle, double squaredDistance,
                                const Points& points) const {
  // The triangle's corners the closest point lies on (weight not zero; 1e-9 is far above the
  // round-off of the weights and far below any meaningful share).
  constexpr double onFeature = 1e-9;
  std::array<int, 3> corners{};
  int count = 0;
  for (std::size_t i = 1; i < 4; ++i)
    if (std::abs(pair.weights[i]) > onFeature) corners[static_cast<std::size_t>(count++)] = pair.points[i];
  if (count == 3 || count == 0) return true;  // inside the face: that triangle's own contact
  const int point = pair.points[0];
  const int n = static_cast<int>(rest_.cols());
  if (count == 1) {
    // Two points: counted once, from the mesh vertex (the smaller one of two mesh vertices).
    const int other = corners[0];
    if ((point >= n && other < n) || (point < n && other < n && point > other)) return false;
  }
  const auto holds = [this](int t, int id) {
    return allTriangles_(0, t) == id || allTriangles_(1, t) == id || allTriangles_(2, t) == id;
  };
  for (const int other : trianglesOfPoint_[static_cast<std::size_t>(corners[0])]) {
    if (other == triangle || (count == 2 && !holds(other, corners[1])) || holds(other, point)) continue;
    const double distance =
        pointTriangleDistanceSquared(points(point), points(allTriangles_(0, other)), points(allTriangles_(1, other)),
                                     points(allTriangles_(2, other)));
    // Another triangle through the edge or corner is closer (the point is over its face or
    // another of its edges): that pair is the contact. As close (to round-off): the first.
    if (distance < squaredDistance * (1.0 - 1e-12)) return false;
    if (distance <= squaredDistance * (1.0 + 1e-12) && other < triangle) return false;
  }
  return true;
}

bool SurfaceContact::timeDependent() const {
  return std::any_of(obstacles_.begin(), obstacles_.end(),
                     [](const MeshObstacle& obstacle) { return obstacle.path.has_value(); });
}

Eigen::Matrix3Xd SurfaceContact::obstaclePositions(double time) const { return pointsAt(time, {}).obstacle; }

SurfaceContact::Points SurfaceContact::pointsAt(double time, const Eigen::VectorXd& displacement) const {
  Points points;
  points.body = rest_;
  if (displacement.size() > 0) {
    if (displacement.size() != rest_.size()) {
      throw ValidationError("surface contact: the displacement has " + std::to_string(displacement.size()) +
                            " entries for " + std::to_string(rest_.cols()) + " vertices");
    }
    points.body += displacement.reshaped(3, rest_.cols());
  }
  points.obstacle.resize(3, static_cast<Eigen::Index>(obstacleOfVertex_.size()));
  const bool moving = timeDependent();
  if (moving) points.obstacleVelocity.setZero(3, points.obstacle.cols());
  Eigen::Index offset = 0;
  for (const MeshObstacle& obstacle : obstacles_) {
    const Eigen::Index m = obstacle.vertices.cols();
    if (!obstacle.path) {
      points.obstacle.middleCols(offset, m) = obstacle.vertices;
    } else {
      Eigen::Matrix3d rotation;
      Eigen::Vector3d translation, angularVelocity, velocity;
      obstacle.path->placement(time, rotation, translation, angularVelocity, velocity);
      for (Eigen::Index k = 0; k < m; ++k) {
        const Eigen::Vector3d turned = rotation * obstacle.vertices.col(k);
        points.obstacle.col(offset + k) = turned + translation;
        points.obstacleVelocity.col(offset + k) = angularVelocity.cross(turned) + velocity;
      }
    }
    offset += m;
  }
  return points;
}

Eigen::Vector3d SurfaceContact::pointVelocity(int id, const Eigen::VectorXd& velocity, const Points& points) {
  const Eigen::Index n = points.body.cols();
  if (id < n) return velocity.segment<3>(3 * static_cast<Eigen::Index>(id));
  if (points.obstacleVelocity.size() == 0) return Eigen::Vector3d::Zero();
  return points.obstacleVelocity.col(id - n);
}

std::shared_ptr<const SurfaceContact::Candidates> SurfaceContact::detect(const Points& points, double distance) const {
  auto found = std::make_shared<Candidates>();
  found->body = points.body;
  found->obstacle = points.obstacle;
  const int n = static_cast<int>(points.body.cols());
  const Eigen::Matrix3Xi& bodyTriangles = bodySurface_.triangles;
  const Eigen::Matrix3Xi& obstacleTriangles = obstacleSurface_.triangles;
  const Eigen::Matrix2Xi& bodyEdges = bodySurface_.edges;
  const Eigen::Matrix2Xi& obstacleEdges = obstacleSurface_.edges;
  if (obstacleSurface_.numTriangles() > 0) {
    const ContactCandidates c = findContactCandidates(bodySurface_, points.body, obstacleSurface_, points.obstacle,
                                                      distance, options_.broadPhase);
    for (const VertexTriangleCandidate& pair : c.firstVerticesSecondTriangles) {
      const auto t = obstacleTriangles.col(pair.triangle);
      found->pointTriangle.push_back({pair.vertex, n + t[0], n + t[1], n + t[2]});
      found->pointTriangleSigned.push_back(obstacleTriangleSigned_[static_cast<std::size_t>(pair.triangle)]);
      found->pointTriangleIndex.push_back(bodySurface_.numTriangles() + pair.triangle);
    }
    for (const VertexTriangleCandidate& pair : c.secondVerticesFirstTriangles) {
      const auto t = bodyTriangles.col(pair.triangle);
      found->pointTriangle.push_back({n + pair.vertex, t[0], t[1], t[2]});
      found->pointTriangleSigned.push_back(1);  // a body's boundary is closed and faces out
      found->pointTriangleIndex.push_back(pair.triangle);
    }
    if (options_.edges) {
      for (const EdgeEdgeCandidate& pair : c.edgeEdge) {
        found->edgeEdge.push_back({bodyEdges(0, pair.first), bodyEdges(1, pair.first),
                                   n + obstacleEdges(0, pair.second), n + obstacleEdges(1, pair.second)});
      }
    }
  }
  if (options_.betweenBodies || options_.self) {
    // Pairs within one object are self-contact: left out unless asked for, and then only
    // where the rest shape keeps them 2 dhat apart (neighbours on a curved surface).
    const double restLimit = 4.0 * options_.thickness * options_.thickness;
    const auto object = [this](int v) { return objectOfVertex_[static_cast<std::size_t>(v)]; };
    const auto wanted = [this](bool same) { return same ? options_.self : options_.betweenBodies; };
    const ContactCandidates c = findSelfContactCandidates(bodySurface_, points.body, distance, options_.broadPhase);
    for (const VertexTriangleCandidate& pair : c.firstVerticesSecondTriangles) {
      const auto t = bodyTriangles.col(pair.triangle);
      const bool same = object(pair.vertex) == object(t[0]);
      if (!wanted(same)) continue;
      if (same && pointTriangleDistanceSquared(rest_.col(pair.vertex), rest_.col(t[0]), rest_.col(t[1]),
                                               rest_.col(t[2])) < restLimit)
        continue;
      found->pointTriangle.push_back({pair.vertex, t[0], t[1], t[2]});
      found->pointTriangleSigned.push_back(same ? 0 : 1);
      found->pointTriangleIndex.push_back(pair.triangle);
    }
    if (options_.edges) {
      for (const EdgeEdgeCandidate& pair : c.edgeEdge) {
        const auto a = bodyEdges.col(pair.first);
        const auto b = bodyEdges.col(pair.second);
        const bool same = object(a[0]) == object(b[0]);
        if (!wanted(same)) continue;
        if (same &&
            edgeEdgeDistanceSquared(rest_.col(a[0]), rest_.col(a[1]), rest_.col(b[0]), rest_.col(b[1])) < restLimit)
          continue;
        found->edgeEdge.push_back({a[0], a[1], b[0], b[1]});
      }
    }
  }
  return found;
}

std::shared_ptr<const SurfaceContact::Candidates> SurfaceContact::candidatesFor(const Points& points) const {
  // A list found at distance 2 dhat holds every pair now closer than dhat while no point
  // has moved more than dhat / 2 since (each pair's distance changed by at most dhat).
  const double reach = 0.5 * options_.thickness;
  std::lock_guard<std::mutex> lock(mutex_);
  const auto movedWithin = [reach](const Eigen::Matrix3Xd& now, const Eigen::Matrix3Xd& then) {
    return now.cols() == then.cols() &&
           (now.cols() == 0 || (now - then).colwise().squaredNorm().maxCoeff() <= reach * reach);
  };
  // The lists kept, most recently used first: a caller that visits several states in turn
  // (an asynchronous step's substeps at every iteration of its contact iteration) finds
  // each one's list again instead of detecting anew (measured on models/collision/strike.json:
  // the broad phase ran at 10,126 of 31,775 evaluations with one list kept, see
  // docs/collision.md).
  for (std::size_t k = 0; k < cached_.size(); ++k) {
    const std::shared_ptr<const Candidates> list = cached_[k];
    if (movedWithin(points.body, list->body) && movedWithin(points.obstacle, list->obstacle)) {
      std::rotate(cached_.begin(), cached_.begin() + static_cast<std::ptrdiff_t>(k),
                  cached_.begin() + static_cast<std::ptrdiff_t>(k) + 1);
      return list;
    }
  }
  cached_.insert(cached_.begin(), detect(points, 2.0 * options_.thickness));
  // Up to 32 lists, fewer where the points kept with them would pass 4 million doubles (32 MB).
  const std::size_t values = 3 * static_cast<std::size_t>(points.body.cols() + points.obstacle.cols());
  const std::size_t kept = std::clamp<std::size_t>(kKeptPointValues / std::max<std::size_t>(values, 1), 2, kKeptLists);
  while (cached_.size() > kept) cached_.pop_back();
  ++stats_.detections;
  stats_.candidates += static_cast<long long>(cached_.front()->pointTriangle.size() + cached_.front()->edgeEdge.size());
  return cached_.front();
}

void SurfaceContact::narrowPhase(const Candidates& candidates, const Points& points, double distance,
                                 std::vector<SurfacePair>& out, const CandidateFilter* keep) const {
  const double limit = distance * distance;
  // Below this the gradient's direction is lost in round-off (q / d is 0 / 0).
  const double smallest = 1e-12 * options_.thickness;
  for (std::size_t k = 0; k < candidates.pointTriangle.size(); ++k) {
    const std::array<int, 4>& ids = candidates.pointTriangle[k];
    if (keep != nullptr && !(*keep)(ids)) continue;
    const Eigen::Vector3d p = points(ids[0]), a = points(ids[1]), b = points(ids[2]), c = points(ids[3]);
    const double q = pointTriangleDistanceSquared(p, a, b, c);
    if (!(q < limit) || !(q > smallest * smallest)) continue;
    const PointTriangleRegion region = pointTriangleRegion(p, a, b, c);
    const bool behind = candidates.pointTriangleSigned[k] != 0 && region == PointTriangleRegion::Face &&
                        (p - a).dot((b - a).cross(c - a)) < 0.0;
    SurfacePair pair = pairFromGradient(ids, pointTriangleDistance(p, a, b, c, region), 1, behind ? -1.0 : 1.0);
    if (countsOnce(pair, candidates.pointTriangleIndex[k], q, points)) out.push_back(pair);
  }
  for (const std::array<int, 4>& ids : candidates.edgeEdge) {
    if (keep != nullptr && !(*keep)(ids)) continue;
    const Eigen::Vector3d a0 = points(ids[0]), a1 = points(ids[1]), b0 = points(ids[2]), b1 = points(ids[3]);
    const double q = edgeEdgeDistanceSquared(a0, a1, b0, b1);
    if (!(q < limit) || !(q > smallest * smallest)) continue;
    // An endpoint's contact is a vertex-triangle pair's (its edge or corner region).
    const EdgeEdgeRegion region = edgeEdgeRegion(a0, a1, b0, b1);
    if (region != EdgeEdgeRegion::Interior) continue;
    const SurfacePair pair = pairFromGradient(ids, edgeEdgeDistance(a0, a1, b0, b1, region), 2, 1.0);
    // Closest points at an endpoint (to round-off): a vertex-triangle pair has it.
    if (std::all_of(pair.weights.begin(), pair.weights.end(), [](double w) { return std::abs(w) > 1e-9; }))
      out.push_back(pair);
  }
}

std::vector<SurfacePair> SurfaceContact::activePairs(double time, const Eigen::VectorXd& displacement, Points* points,
                                                     const CandidateFilter* keep) const {
  const Clock::time_point start = Clock::now();
  Points local = pointsAt(time, displacement);
  Points& at = points != nullptr ? (*points = std::move(local)) : local;
  const std::shared_ptr<const Candidates> candidates = candidatesFor(at);
  std::vector<SurfacePair> pairs;
  narrowPhase(*candidates, at, options_.thickness, pairs, keep);
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.detectionSeconds += seconds;
  return pairs;
}

std::vector<SurfacePair> SurfaceContact::pairs(double time, const Eigen::VectorXd& displacement) const {
  return activePairs(time, displacement, nullptr);
}

namespace {

// Whether mesh vertex id is one the caller asked for (all when vertices is null).
class VertexFilter {
 public:
  VertexFilter(const std::vector<int>* vertices, int numVertices) : numVertices_(numVertices) {
    if (vertices == nullptr) return;
    marked_.assign(static_cast<std::size_t>(numVertices), 0);
    for (const int v : *vertices) marked_[static_cast<std::size_t>(v)] = 1;
  }
  bool operator()(int id) const {
    return id < numVertices_ && (marked_.empty() || marked_[static_cast<std::size_t>(id)] != 0);
  }

 private:
  int numVertices_;
  std::vector<char> marked_;
};

}  // namespace

SurfaceContact::CandidateFilter SurfaceContact::ownedBy(const std::vector<int>& rank, int owner) const {
  const int n = static_cast<int>(rest_.cols());
  if (rank.size() != static_cast<std::size_t>(n))
    throw ValidationError("surface contact: " + std::to_string(rank.size()) + " vertex ranks for " + std::to_string(n) +
                          " vertices");
  return [&rank, owner, n](const std::array<int, 4>& points) {
    int highest = std::numeric_limits<int>::min();
    for (const int id : points)
      if (id < n) highest = std::max(highest, rank[static_cast<std::size_t>(id)]);
    return highest == owner;
  };
}

template <class Wanted>
void SurfaceContact::addPairForces(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                                   Eigen::VectorXd& forces, const CandidateFilter* keep, Wanted&& wanted,
                                   VertexJacobian* couplings) const {
  Points points;
  const std::vector<SurfacePair> found = activePairs(time, displacement, &points, keep);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.evaluations;
    stats_.activePairs += static_cast<long long>(found.size());
    stats_.largestActive = std::max(stats_.largestActive, static_cast<long long>(found.size()));
  }
  for (const SurfacePair& pair : found) {
    Eigen::Vector3d relative = Eigen::Vector3d::Zero();
    for (int i = 0; i < 4; ++i)
      relative += pair.weights[static_cast<std::size_t>(i)] *
                  pointVelocity(pair.points[static_cast<std::size_t>(i)], velocity, points);
    const double normalSpeed = pair.normal.dot(relative);
    const double normalForce = (stiffness_ * (options_.thickness - pair.gap)) - (damping_ * normalSpeed);
    if (!(normalForce > 0.0)) continue;  // the clamp: contact pushes, never pulls
    if (couplings != nullptr) couplings->couplings.push_back(couplingOf(pair));
    Eigen::Vector3d f = normalForce * pair.normal;
    if (friction_ > 0.0) {
      const Eigen::Vector3d tangential = relative - normalSpeed * pair.normal;
      const double speed = tangential.norm();
      if (speed > 0.0) f -= (std::min(friction_ * normalForce, frictionViscosity_ * speed) / speed) * tangential;
    }
    for (int i = 0; i < 4; ++i) {
      const int id = pair.points[static_cast<std::size_t>(i)];
      if (wanted(id))
        forces.segment<3>(3 * static_cast<Eigen::Index>(id)) += pair.weights[static_cast<std::size_t>(i)] * f;
    }
  }
}

void SurfaceContact::addForces(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                               Eigen::VectorXd& forces, const std::vector<int>* vertices) const {
  const VertexFilter wanted(vertices, static_cast<int>(rest_.cols()));
  addPairForces(time, displacement, velocity, forces, nullptr, wanted, nullptr);
}

void SurfaceContact::addForcesOfRank(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                                     const std::vector<int>& rank, int owner, Eigen::VectorXd& forces,
                                     VertexJacobian* couplings) const {
  const int n = static_cast<int>(rest_.cols());
  const CandidateFilter keep = ownedBy(rank, owner);
  addPairForces(
      time, displacement, velocity, forces, &keep, [n](int id) { return id < n; }, couplings);
}

VertexCoupling SurfaceContact::couplingOf(const SurfacePair& pair) const {
  const int n = static_cast<int>(rest_.cols());
  VertexCoupling coupling;
  for (std::size_t i = 0; i < 4; ++i) {
    coupling.vertices[i] = pair.points[i] < n ? pair.points[i] : -1;  // an obstacle point is no DOF
    coupling.weights[i] = pair.weights[i];
  }
  coupling.direction = pair.normal;
  coupling.stiffness = stiffness_;
  coupling.damping = damping_;
  return coupling;
}

void SurfaceContact::addJacobian(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                                 VertexJacobian& jacobian, const std::vector<int>* vertices) const {
  Points points;
  const std::vector<SurfacePair> found = activePairs(time, displacement, &points);
  const int n = static_cast<int>(rest_.cols());
  const VertexFilter wanted(vertices, n);
  for (const SurfacePair& pair : found) {
    Eigen::Vector3d relative = Eigen::Vector3d::Zero();
    double meshWeights = 0.0;
    for (int i = 0; i < 4; ++i) {
      const int id = pair.points[static_cast<std::size_t>(i)];
      relative += pair.weights[static_cast<std::size_t>(i)] * pointVelocity(id, velocity, points);
      if (id < n) meshWeights += std::abs(pair.weights[static_cast<std::size_t>(i)]);
    }
    const double normalForce = (stiffness_ * (options_.thickness - pair.gap)) - (damping_ * pair.normal.dot(relative));
    if (!(normalForce > 0.0)) continue;  // clamped: no force, no derivative
    const Eigen::Matrix3d normalBlock = pair.normal * pair.normal.transpose();
    for (int i = 0; i < 4; ++i) {
      const int id = pair.points[static_cast<std::size_t>(i)];
      if (!wanted(id)) continue;
      const double scale = std::abs(pair.weights[static_cast<std::size_t>(i)]) * meshWeights;
      jacobian.vertices.push_back(id);
      jacobian.stiffness.push_back(stiffness_ * scale * normalBlock);
      jacobian.damping.push_back(damping_ * scale * normalBlock);
    }
  }
}

void SurfaceContact::addCoupledJacobian(double time, const Eigen::VectorXd& displacement,
                                        const Eigen::VectorXd& velocity, VertexJacobian& jacobian) const {
  Points points;
  const std::vector<SurfacePair> found = activePairs(time, displacement, &points);
  for (const SurfacePair& pair : found) {
    Eigen::Vector3d relative = Eigen::Vector3d::Zero();
    for (int i = 0; i < 4; ++i) {
      relative += pair.weights[static_cast<std::size_t>(i)] *
                  pointVelocity(pair.points[static_cast<std::size_t>(i)], velocity, points);
    }
    const double normalForce = (stiffness_ * (options_.thickness - pair.gap)) - (damping_ * pair.normal.dot(relative));
    if (!(normalForce > 0.0)) continue;  // clamped: no force, no derivative
    jacobian.couplings.push_back(couplingOf(pair));
  }
}

double SurfaceContact::energy(double time, const Eigen::VectorXd& displacement) const {
  double squares = 0.0;
  for (const SurfacePair& pair : activePairs(time, displacement, nullptr)) {
    squares += (options_.thickness - pair.gap) * (options_.thickness - pair.gap);
  }
  return 0.5 * stiffness_ * squares;
}

double SurfaceContact::maxDepth(double time, const Eigen::VectorXd& displacement) const {
  double deepest = 0.0;
  for (const SurfacePair& pair : activePairs(time, displacement, nullptr)) {
    deepest = std::max(deepest, options_.thickness - pair.gap);
  }
  return deepest;
}

std::vector<int> SurfaceContact::verticesWithin(double time, const Eigen::VectorXd& displacement, double margin) const {
  const double distance = options_.thickness + (2.0 * std::max(0.0, margin));
  const Points points = pointsAt(time, displacement);
  std::vector<SurfacePair> near;
  narrowPhase(*detect(points, distance), points, distance, near);
  std::vector<int> out;
  const int n = static_cast<int>(rest_.cols());
  for (const SurfacePair& pair : near)
    for (const int id : pair.points)
      if (id < n) out.push_back(id);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

SurfaceContactStats SurfaceContact::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

}  // namespace asyncfem
