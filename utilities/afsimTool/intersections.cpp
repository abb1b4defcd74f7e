// SPDX-License-Identifier: BSD-3-Clause
#include "intersections.hpp"

#include <asyncfem/collision/collisionSurface.hpp>
#include <asyncfem/collision/triangleIntersection.hpp>
#include <asyncfem/contact/penaltyContact.hpp>
#include <asyncfem/contact/surfaceContact.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/simulationIO/frameSelection.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <cstdio>
#include <iostream>

namespace afsimtool {

using namespace asyncfem;

namespace {

/// The scene given, else the one the file records (its mesh checked by the fingerprint).
Scene sceneFor(const SimulationReader& reader, const std::optional<std::string>& scene) {
  if (scene) return loadScene(*scene);
  if (reader.header().scenePath.empty()) {
    throw Error(reader.path().string() + " records no scene: give it with --scene SCENE.json");
  }
  (void)recordedSceneProblem(reader.header(), reader.path().string());  // throws if the scene changed
  return loadScene(reader.header().scenePath);
}

}  // namespace

int intersections(const std::string& simulation, const std::optional<std::string>& scenePath,
                  const std::string& frameText) {
  SimulationReader reader(simulation);
  const Scene scene = sceneFor(reader, scenePath);
  const Simulation built = buildSimulation(scene);
  const TetMesh& mesh = *built.mesh;
  if (mesh.numVertices() != reader.numVertices()) {
    throw Error(simulation + " has " + std::to_string(reader.numVertices()) + " vertices but the scene (" +
                scene.sourceName + ") builds " + std::to_string(mesh.numVertices()) +
                ": the simulation did not run on it");
  }
  const SurfaceContact* surfaces = built.contact ? built.contact->surfaces().get() : nullptr;
  const CollisionSurface bodies = surfaces ? surfaces->bodySurface() : boundarySurface(mesh);
  const std::vector<std::int64_t> frames =
      frames::selectFrames(frames::parseFrameSelection(frameText), reader.numFrames(), simulation);
  std::cout << "frame,time,bodyPairs,obstaclePairs,contactDepth\n";
  SimulationFrame frame;
  std::int64_t intersecting = 0, worstFrame = -1, deepestFrame = -1;
  std::size_t worstPairs = 0;
  double deepest = 0.0;
  for (const std::int64_t k : frames) {
    reader.readFrame(k, frame);
    Eigen::Matrix3Xd positions = mesh.restPositions();
    positions += frame.displacement.reshaped(3, mesh.numVertices());
    const std::size_t bodyPairs = selfIntersectingTrianglePairs(bodies, positions).size();
    std::size_t obstaclePairs = 0;
    if (surfaces && surfaces->obstacleSurface().numTriangles() > 0) {
      obstaclePairs = intersectingTrianglePairs(bodies, positions, surfaces->obstacleSurface(),
                                                surfaces->obstaclePositions(frame.time))
                          .size();
    }
    const double penetration = built.contact ? built.contact->maxPenetration(frame.time, frame.displacement) : 0.0;
    std::printf("%lld,%.9g,%zu,%zu,%.6g\n", static_cast<long long>(k), frame.time, bodyPairs, obstaclePairs,
                penetration);
    if (bodyPairs + obstaclePairs > 0) ++intersecting;
    if (bodyPairs + obstaclePairs > worstPairs) {
      worstPairs = bodyPairs + obstaclePairs;
      worstFrame = k;
    }
    if (penetration > deepest) {
      deepest = penetration;
      deepestFrame = k;
    }
  }
  std::fflush(stdout);
  std::cerr << "intersections: " << intersecting << " of " << frames.size() << " frames have intersecting triangles";
  if (worstFrame >= 0) std::cerr << " (most: " << worstPairs << " pairs at frame " << worstFrame << ")";
  std::cerr << "; deepest contact depth " << deepest;
  if (deepestFrame >= 0) std::cerr << " at frame " << deepestFrame;
  std::cerr << '\n';
  return 0;
}

}  // namespace afsimtool
