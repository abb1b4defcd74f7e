// SPDX-License-Identifier: BSD-3-Clause
// The loads policy of run-time regions: docs/asynchronous-integrator.md, "Run-time regions".
#include <Eigen/Dense>
#include <algorithm>
#include <asyncfem/asyncIntegrator/loadsPolicy.hpp>
#include <asyncfem/core/error.hpp>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <string>

#include "detail/meshElements.hpp"

namespace asyncfem {

Eigen::VectorXd lumpedVertexMasses(const TetMesh& mesh) {
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(mesh.numVertices());
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Eigen::VectorXd share = detail::vertexMassesOf(mesh, e);
    for (int a = 0; a < mesh.verticesPerElement(); ++a) mass[mesh.elementVertex(e, a)] += share[a];
  }
  return mass;
}

double relativeMotionEnergy(const TetMesh& mesh, const Eigen::VectorXd& vertexMass, const std::vector<int>& part,
                            const std::vector<int>& neighbourhood, const Eigen::VectorXd& u, const Eigen::VectorXd& v) {
  const auto position = [&](int i) -> Eigen::Vector3d {
    return mesh.restPosition(i) + u.segment<3>(3 * static_cast<Eigen::Index>(i));
  };
  const auto velocity = [&](int i) -> Eigen::Vector3d { return v.segment<3>(3 * static_cast<Eigen::Index>(i)); };
  double total = 0.0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(), momentum = Eigen::Vector3d::Zero();
  for (const int i : neighbourhood) {
    total += vertexMass[i];
    centre += vertexMass[i] * position(i);
    momentum += vertexMass[i] * velocity(i);
  }
  Eigen::Vector3d meanVelocity = Eigen::Vector3d::Zero(), spin = Eigen::Vector3d::Zero();
  if (total > 0.0) {
    centre /= total;
    meanVelocity = momentum / total;
    Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
    Eigen::Vector3d angular = Eigen::Vector3d::Zero();
    for (const int i : neighbourhood) {
      const Eigen::Vector3d r = position(i) - centre;
      inertia += vertexMass[i] * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
      angular += vertexMass[i] * r.cross(velocity(i) - meanVelocity);
    }
    // w = I^{-1} L on the range of I (a line of vertices cannot spin about itself).
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(inertia);
    const double cutoff = 1e-12 * std::max(eigen.eigenvalues().maxCoeff(), 0.0);
    for (int k = 0; k < 3; ++k) {
      const double lambda = eigen.eigenvalues()[k];
      if (lambda > cutoff) spin += eigen.eigenvectors().col(k) * (eigen.eigenvectors().col(k).dot(angular) / lambda);
    }
  }
  double energy = 0.0;
  for (const int i : part) {
    const Eigen::Vector3d relative = velocity(i) - meanVelocity - spin.cross(position(i) - centre);
    energy += 0.5 * vertexMass[i] * relative.squaredNorm();
  }
  return energy;
}

std::vector<int> verticesReachedByLoads(const ExternalForceFunction& force, const ExternalForceChanges& changes,
                                        double from, double t0, double largeStep, int ratio, const Eigen::VectorXd& u,
                                        const Eigen::VectorXd& v) {
  std::vector<int> reached;
  if (!force || ratio < 1) return reached;
  const double t1 = t0 + largeStep;
  if (changes && !changes(from, t1)) return reached;
  Eigen::VectorXd start = Eigen::VectorXd::Zero(u.size());
  force(from, u, v, start);
  std::vector<char> differs(static_cast<std::size_t>(u.size() / 3), 0);
  Eigen::VectorXd at(u.size());
  const double smallStep = largeStep / ratio;
  for (int r = 1; r <= ratio; ++r) {
    at.setZero();
    force(r == ratio ? t1 : t0 + r * smallStep, u, v, at);  // the substep times of a region of this ratio
    for (Eigen::Index dof = 0; dof < u.size(); ++dof)
      if (at[dof] != start[dof]) differs[static_cast<std::size_t>(dof / 3)] = 1;
  }
  for (std::size_t vertex = 0; vertex < differs.size(); ++vertex)
    if (differs[vertex]) reached.push_back(static_cast<int>(vertex));
  return reached;
}

LoadsPolicy::LoadsPolicy(const TetMesh& mesh, std::vector<char> hasFreeDof, LoadsPolicySettings settings)
    : mesh_(&mesh), hasFreeDof_(std::move(hasFreeDof)), settings_(std::move(settings)) {
  const LoadsPolicySettings& s = settings_;
  if (s.ratio < 2 || s.rings < 0 || s.neighbourhood < 0 || s.minDwell < 0) {
    throw ValidationError("run-time regions: loads: ratio must be >= 2 and rings, neighbourhood and minDwell >= 0");
  }
  if (!(s.release >= 0.0 && s.release < 1.0)) {
    throw ValidationError("run-time regions: loads: release must be in [0, 1) (a fraction of the peak energy)");
  }
  vertexMass_ = lumpedVertexMasses(mesh);
  partsOfVertex_.assign(static_cast<std::size_t>(mesh.numVertices()), {});
  probeRatio_ = s.ratio;
  for (std::size_t k = 0; k < s.parts.size(); ++k) {
    const AsyncRegion& part = s.parts[k];
    const std::string where = "run-time regions: loads: part " + std::to_string(k);
    if (part.ratio < 2) throw ValidationError(where + ": ratio must be >= 2");
    for (const int vertex : part.vertices) {
      if (vertex < 0 || vertex >= mesh.numVertices()) {
        throw ValidationError(where + ": vertex " + std::to_string(vertex) + " out of range (the mesh has " +
                              std::to_string(mesh.numVertices()) + " vertices)");
      }
    }
    addPart(part.name.empty() ? "part" + std::to_string(k) : part.name, part.vertices, part.ratio);
    probeRatio_ = std::max(probeRatio_, part.ratio);
  }
  givenParts_ = static_cast<int>(parts_.size());
}

void LoadsPolicy::setExternalForce(ExternalForceFunction force, ExternalForceChanges changes) {
  force_ = std::move(force);
  changes_ = std::move(changes);
}

int LoadsPolicy::addPart(std::string name, std::vector<int> vertices, int ratio) {
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  Part part;
  part.name = std::move(name);
  part.ratio = ratio;
  std::vector<char> around(static_cast<std::size_t>(mesh_->numVertices()), 0);
  for (const int vertex : vertices) around[static_cast<std::size_t>(vertex)] = 1;
  growByRings(*mesh_, around, settings_.neighbourhood);
  for (std::size_t vertex = 0; vertex < around.size(); ++vertex)
    if (around[vertex]) part.neighbourhood.push_back(static_cast<int>(vertex));
  const auto index = static_cast<int>(parts_.size());
  for (const int vertex : vertices) partsOfVertex_[static_cast<std::size_t>(vertex)].push_back(index);
  part.vertices = std::move(vertices);
  parts_.push_back(std::move(part));
  return index;
}

namespace {
/// The marked vertices in sets connected through elements, each sorted.
std::vector<std::vector<int>> components(const TetMesh& mesh, const std::vector<char>& marked) {
  std::vector<int> parent(marked.size());
  std::iota(parent.begin(), parent.end(), 0);
  const auto root = [&](int i) {
    while (parent[static_cast<std::size_t>(i)] != i)
      i = parent[static_cast<std::size_t>(i)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    return i;
  };
  for (int e = 0; e < mesh.numElements(); ++e) {
    int first = -1;
    for (int a = 0; a < mesh.verticesPerElement(); ++a) {
      const int vertex = mesh.elementVertex(e, a);
      if (!marked[static_cast<std::size_t>(vertex)]) continue;
      if (first < 0) {
        first = vertex;
      } else {
        parent[static_cast<std::size_t>(root(vertex))] = root(first);
      }
    }
  }
  std::vector<std::vector<int>> out;
  std::vector<int> slot(marked.size(), -1);
  for (std::size_t vertex = 0; vertex < marked.size(); ++vertex) {
    if (!marked[vertex]) continue;
    int& s = slot[static_cast<std::size_t>(root(static_cast<int>(vertex)))];
    if (s < 0) {
      s = static_cast<int>(out.size());
      out.emplace_back();
    }
    out[static_cast<std::size_t>(s)].push_back(static_cast<int>(vertex));
  }
  return out;
}

std::string formatTime(double time) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4f", time);
  return text;
}
}  // namespace

void LoadsPolicy::switchFast(double t0, double largeStep, const std::vector<int>& reached,
                             std::vector<std::string>& why) {
  // Reached vertices no given part holds: their own parts, grown by rings, per component;
  // one whose reached vertices an earlier such part holds reuses it.
  std::vector<int> count(parts_.size(), 0);
  std::vector<char> loose(static_cast<std::size_t>(mesh_->numVertices()), 0);
  for (const int vertex : reached) {
    bool held = false;
    for (const int p : partsOfVertex_[static_cast<std::size_t>(vertex)]) {
      ++count[static_cast<std::size_t>(p)];
      held = held || p < givenParts_;
    }
    if (!held) loose[static_cast<std::size_t>(vertex)] = 1;
  }
  for (std::vector<int>& core : components(*mesh_, loose)) {
    int reuse = -1;
    for (int p = givenParts_; p < static_cast<int>(parts_.size()) && reuse < 0; ++p) {
      const std::vector<int>& held = parts_[static_cast<std::size_t>(p)].vertices;
      if (std::includes(held.begin(), held.end(), core.begin(), core.end())) reuse = p;
    }
    if (reuse >= 0) continue;  // counted above
    std::vector<char> grown(static_cast<std::size_t>(mesh_->numVertices()), 0);
    for (const int vertex : core) grown[static_cast<std::size_t>(vertex)] = 1;
    growByRings(*mesh_, grown, settings_.rings);
    std::vector<int> vertices;
    for (std::size_t vertex = 0; vertex < grown.size(); ++vertex)
      if (grown[vertex]) vertices.push_back(static_cast<int>(vertex));
    const int p = addPart("loaded" + std::to_string(parts_.size() - static_cast<std::size_t>(givenParts_) + 1),
                          std::move(vertices), settings_.ratio);
    count.push_back(static_cast<int>(core.size()));
    (void)p;
  }
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    if (count[p] == 0) continue;
    Part& part = parts_[p];
    part.peak = 0.0;  // a new load change: the decay is measured from here
    part.quiet = 0;
    if (part.fast) continue;
    part.fast = true;
    LoadsSwitch record;
    record.time = t0;
    record.part = part.name;
    record.fast = true;
    record.reachedVertices = count[p];
    record.text = "loads: part '" + part.name + "' fast from t = " + formatTime(t0) +
                  " s, m = " + std::to_string(part.ratio) + " (a load reaches " + std::to_string(count[p]) +
                  " of its " + std::to_string(part.vertices.size()) + " vertices in (" + formatTime(t0) + ", " +
                  formatTime(t0 + largeStep) + "] s)";
    why.push_back(record.text);
    switches_.push_back(std::move(record));
  }
}

void LoadsPolicy::releaseQuiet(double t0, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                               const std::vector<char>& touched, std::vector<std::string>& why) {
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    Part& part = parts_[p];
    if (!part.fast || (p < touched.size() && touched[p])) continue;
    const double energy = relativeMotionEnergy(*mesh_, vertexMass_, part.vertices, part.neighbourhood, u, v);
    part.peak = std::max(part.peak, energy);
    part.quiet = energy <= settings_.release * part.peak ? part.quiet + 1 : 0;
    if (part.quiet < settings_.minDwell) continue;
    part.fast = false;
    part.quiet = 0;
    LoadsSwitch record;
    record.time = t0;
    record.part = part.name;
    record.energy = energy;
    record.peak = part.peak;
    char text[400];
    std::snprintf(text, sizeof text,
                  "loads: part '%s' released at t = %s s (its motion relative to its neighbourhood's rigid motion, "
                  "%.3g J, has stayed at or below %g of its peak %.3g J for %d large steps)",
                  part.name.c_str(), formatTime(t0).c_str(), energy, settings_.release, part.peak, settings_.minDwell);
    record.text = text;
    why.push_back(record.text);
    switches_.push_back(std::move(record));
  }
}

bool LoadsPolicy::update(double t0, double largeStep, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                         std::string& reason) {
  if (t0 == lastTime_) return false;  // the same boundary again (a set-up before its first step)
  if (t0 < lastTime_) {               // not a continuation: start over
    for (Part& part : parts_) part = Part{part.name, part.vertices, part.ratio, part.neighbourhood};
    lastTime_ = -std::numeric_limits<double>::infinity();
  }
  // The first boundary compares with the force just before it, so that a load that starts
  // with the run (a window from t = 0) counts as starting in the first step.
  const bool first = !std::isfinite(lastTime_) || t0 < lastTime_;
  const double from = first ? t0 - largeStep / probeRatio_ : t0;
  std::vector<int> reached = verticesReachedByLoads(force_, changes_, from, t0, largeStep, probeRatio_, u, v);
  lastTime_ = t0;
  reached.erase(std::remove_if(reached.begin(), reached.end(),
                               [&](int vertex) { return !hasFreeDof_[static_cast<std::size_t>(vertex)]; }),
                reached.end());
  const std::size_t before = switches_.size();
  std::vector<std::string> why;
  switchFast(t0, largeStep, reached, why);
  std::vector<char> touched(parts_.size(), 0);
  for (const int vertex : reached)
    for (const int p : partsOfVertex_[static_cast<std::size_t>(vertex)]) touched[static_cast<std::size_t>(p)] = 1;
  releaseQuiet(t0, u, v, touched, why);
  if (switches_.size() == before) return false;
  reason.clear();
  for (const std::string& text : why) reason += (reason.empty() ? "" : "; ") + text;
  return true;
}

std::vector<AsyncRegion> LoadsPolicy::regions() const {
  std::vector<AsyncRegion> out;
  for (const Part& part : parts_)
    if (part.fast) out.push_back({part.name, part.vertices, part.ratio});
  return out;
}

std::vector<int> LoadsPolicy::partVertices() const {
  std::vector<int> out;
  for (const Part& part : parts_) out.insert(out.end(), part.vertices.begin(), part.vertices.end());
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace asyncfem
