// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/benchmarkTools/sceneReference.hpp>
#include <asyncfem/core/error.hpp>
#include <cmath>
#include <map>

namespace asyncfem {

std::string modalReferenceUnsupportedReason(const Scene& scene, const Simulation& simulation, int maxFreeDofs) {
  if (scene.forceModel != Scene::ForceModelKind::linear) return "nonlinear force model";
  if (scene.contact.enabled()) return "contact forces depend on the state";
  const int numFree = simulation.integrator->system().freeDofs.numFree();
  if (numFree > maxFreeDofs) {
    return std::to_string(numFree) + " free DOFs exceed the dense-eigendecomposition limit of " +
           std::to_string(maxFreeDofs);
  }
  return "";
}

namespace {

std::vector<int> loadVertices(const Scene& scene, const TetMesh& mesh, const Scene::Force& force, std::size_t index) {
  std::vector<int> vertices;
  if (!force.set.empty()) {
    const auto it = mesh.vertexSets().find(force.set);
    if (it == mesh.vertexSets().end() || it->second.empty()) {
      throw ValidationError(scene.sourceName + ": forces[" + std::to_string(index) +
                            "].set: unknown or empty vertex set \"" + force.set + "\"");
    }
    vertices = it->second;
  } else {
    vertices = force.vertices;
  }
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  return vertices;
}

}  // namespace

PiecewiseConstantLoad sceneLoad(const Scene& scene, const Simulation& simulation) {
  const TetMesh& mesh = *simulation.mesh;
  const int numDofs = mesh.numDofs();
  Eigen::VectorXd gravityForce = Eigen::VectorXd::Zero(numDofs);
  if (!scene.gravity.isZero(0.0)) {
    gravityForce = simulation.integrator->system().mass * scene.gravity.replicate(mesh.numVertices(), 1);
  }
  struct Pull {
    std::vector<int> vertices;
    Eigen::Vector3d perVertex;
    double start, end;
  };
  std::vector<Pull> pulls;
  PiecewiseConstantLoad load;
  std::vector<double> breakpoints;
  for (std::size_t i = 0; i < scene.forces.size(); ++i) {
    const Scene::Force& force = scene.forces[i];
    const std::vector<int> vertices = loadVertices(scene, mesh, force, i);
    const double count = static_cast<double>(vertices.size());
    if (force.type == Scene::ForceType::pull) {
      pulls.push_back({vertices, force.vector / count, force.start, force.end});
      for (const double t : {force.start, force.end}) {
        if (t > 0.0 && std::isfinite(t)) breakpoints.push_back(t);
      }
    } else {
      PiecewiseConstantLoad::Impulse impulse;
      impulse.time = force.time;
      impulse.impulse = Eigen::VectorXd::Zero(numDofs);
      for (const int v : vertices) impulse.impulse.segment<3>(3 * static_cast<Eigen::Index>(v)) += force.vector / count;
      load.impulses.push_back(std::move(impulse));
    }
  }
  std::sort(breakpoints.begin(), breakpoints.end());
  breakpoints.erase(std::unique(breakpoints.begin(), breakpoints.end()), breakpoints.end());
  load.breakpoints = breakpoints;
  // The force on each piece: what is active at its start (pulls act on start <= t < end).
  for (std::size_t k = 0; k <= breakpoints.size(); ++k) {
    const double pieceStart = k == 0 ? 0.0 : breakpoints[k - 1];
    Eigen::VectorXd f = gravityForce;
    for (const Pull& pull : pulls) {
      if (pull.start <= pieceStart && pieceStart < pull.end) {
        for (const int v : pull.vertices) f.segment<3>(3 * static_cast<Eigen::Index>(v)) += pull.perVertex;
      }
    }
    load.forces.push_back(std::move(f));
  }
  return load;
}

std::vector<double> frameTimes(const Scene& scene, int count) {
  std::vector<double> times(static_cast<std::size_t>(std::max(0, count)));
  for (int k = 0; k < count; ++k) times[static_cast<std::size_t>(k)] = (k + 1) / scene.timing.frameRate;
  return times;
}

}  // namespace asyncfem
