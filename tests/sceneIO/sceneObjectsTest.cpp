// SPDX-License-Identifier: BSD-3-Clause
// Scenes of several bodies (objects) and mesh obstacles: the combined mesh, the errors, and
// a head-on collision of two bodies through surface contact.
#include <gtest/gtest.h>

#include <asyncfem/contact/surfaceContact.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/sceneIO/sceneObjects.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/tetMesher/triangleSurface.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <cmath>
#include <iostream>
#include <map>
#include <numbers>
#include <sstream>

#include "sceneTestUtilities.hpp"

namespace asyncfem {
namespace {

using nlohmann::json;

// Half a turn about (0, 1, 1): x -> -x, y <-> z. It maps the left box below onto the
// right one and back, so the pair is point-symmetric; it also swaps the cross-section's
// axes, so that with the offset in y the two boxes' surface grids do not line up (every
// vertex opposite a vertex would make each contact a tie between primitives).
const Eigen::Matrix3d kTurn =
    Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d(0, 1, 1).normalized()).toRotationMatrix();

// Two unit boxes of 2^3 cells, the second the first turned by kTurn, `gap` apart along x,
// moving at `speed` towards each other.
json twoBoxes(double gap, double speed) {
  const Eigen::Vector3d left(-1 - gap / 2, -0.37, -0.5);
  const Eigen::Vector3d right = kTurn * left;
  json scene = json::parse(R"({
    "objects": [
      {"name": "left", "mesh": {"generator": "box", "size": [1, 1, 1], "cells": [2, 2, 2],
        "material": {"name": "rubber", "density": 1000, "youngsModulus": 1e5, "poissonRatio": 0.3}}},
      {"name": "right", "mesh": {"generator": "box", "size": [1, 1, 1], "cells": [2, 2, 2],
        "material": {"name": "rubber", "density": 1000, "youngsModulus": 1e5, "poissonRatio": 0.3}},
       "rotation": {"axis": [0, 1, 1], "angle": 180}}
    ],
    "contact": {"surfaces": {"thickness": 0.05}, "stiffness": 2e5},
    "integrator": {"name": "backward-euler", "timestep": 0.0016666666666666668},
    "frames": {"rate": 60, "count": 2}
  })");
  scene["objects"][0]["translation"] = {left.x(), left.y(), left.z()};
  scene["objects"][0]["velocity"] = {speed, 0, 0};
  scene["objects"][1]["translation"] = {right.x(), right.y(), right.z()};
  scene["objects"][1]["velocity"] = {-speed, 0, 0};
  return scene;
}

std::string errorOf(const json& scene) {
  try {
    (void)buildSimulation(parseScene(scene, "", "s.json"));
  } catch (const Error& error) {
    return error.what();
  }
  return "no error";
}

TEST(SceneObjects, ObjectsBecomeOneMeshWithTheirNamesAsSets) {
  json scene = twoBoxes(0.1, 0.0);
  scene["objects"][1]["scale"] = 0.5;
  scene["objects"][0]["fixed"] = json::parse(R"({"boxes": [{"min": [0, 0, 0], "max": [0, 1, 1]}]})");
  const Scene parsed = parseScene(scene, "", "s.json");
  ASSERT_EQ(parsed.objects.size(), 2u);
  const TetMesh mesh = buildSceneMesh(parsed);
  BoxMeshSpec spec;
  spec.cells = Eigen::Vector3i::Constant(2);
  const TetMesh box = makeBoxMesh(spec);
  ASSERT_EQ(mesh.numVertices(), 2 * box.numVertices());
  ASSERT_EQ(mesh.numElements(), 2 * box.numElements());
  EXPECT_EQ(mesh.vertexSet("left").size(), static_cast<std::size_t>(box.numVertices()));
  EXPECT_EQ(mesh.elementSet("right").front(), box.numElements());
  EXPECT_EQ(mesh.vertexSet("right/xmin").front(), box.numVertices() + box.vertexSet("xmin").front());
  // The right box: turned, halved, moved; rounding of the rotation matrix only.
  const Eigen::Vector3d translation = kTurn * Eigen::Vector3d(-1.05, -0.37, -0.5);
  for (int v = 0; v < box.numVertices(); ++v) {
    const Eigen::Vector3d expected = translation + kTurn * (0.5 * box.restPositions().col(v));
    EXPECT_LE((mesh.restPositions().col(box.numVertices() + v) - expected).norm(), 1e-15);
  }
  // Fixed: left's x = 0 face, in its own coordinates, as the vertex set left/fixed.
  const std::shared_ptr<const Problem> problem = buildProblem(parsed);
  EXPECT_EQ(problem->fixedVertices(), box.vertexSet("xmin"));
  // Each object keeps its material, named after it.
  EXPECT_EQ(mesh.materials().at(1).name, "right/rubber");
}

TEST(SceneObjects, ObjectsThatStartInterpenetratingAreRefusedByName) {
  const std::string message = errorOf(twoBoxes(-0.2, 0.0));
  EXPECT_NE(message.find("s.json: objects: objects[0] 'left' and objects[1] 'right' start interpenetrating: triangle "),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("of 'right' (its vertices"), std::string::npos) << message;
}

TEST(SceneObjects, BadObjectAndObstacleKeysAreNamed) {
  json both = twoBoxes(0.1, 0.0);
  both["mesh"] = json::parse(R"({"generator": "box"})");
  EXPECT_NE(errorOf(both).find("s.json: mesh: give either \"mesh\" (one body) or \"objects\""), std::string::npos)
      << errorOf(both);
  json twice = twoBoxes(0.1, 0.0);
  twice["objects"][1]["name"] = "left";
  EXPECT_NE(errorOf(twice).find("objects[1].name: \"left\" names two objects or obstacles"), std::string::npos)
      << errorOf(twice);
  json unknownSet = twoBoxes(0.1, 0.0);
  unknownSet["objects"][1]["fixed"] = json::parse(R"({"sets": ["nowhere"]})");
  EXPECT_NE(errorOf(unknownSet).find("s.json: objects[1].fixed.sets[0]: "), std::string::npos) << errorOf(unknownSet);
  json oneKey = twoBoxes(0.1, 0.0);
  oneKey["contact"]["obstacles"] =
      json::parse(R"([{"name": "bar", "file": "bar.obj", "path": [{"time": 0, "translation": [0, 0, 0]}]}])");
  EXPECT_NE(errorOf(oneKey).find("s.json: contact.obstacles[0].path: a moving obstacle's path needs at least two "
                                 "keys (got 1)"),
            std::string::npos)
      << errorOf(oneKey);
  json missing = twoBoxes(0.1, 0.0);
  missing["contact"]["obstacles"] = json::parse(R"([{"name": "bowl", "file": "no-such-bowl.obj"}])");
  const std::string missingMessage = errorOf(missing);
  EXPECT_NE(missingMessage.find("s.json: contact.obstacles[0].file: "), std::string::npos) << missingMessage;
  EXPECT_NE(missingMessage.find("no-such-bowl.obj"), std::string::npos) << missingMessage;
}

TEST(SceneObjects, AnOpenObstacleThatMustBeClosedIsRefused) {
  if (!surfaceReaderAvailable()) GTEST_SKIP() << "this build reads no surfaces (no assimp)";
  const test::ScratchFolder folder;
  // One triangle: open.
  const std::filesystem::path file = folder.write("sheet.obj", "v 0 -1 0\nv 1 -1 0\nv 0 -1 1\nf 1 2 3\n");
  json scene = twoBoxes(0.1, 0.0);
  scene["contact"]["obstacles"] = {{{"name", "sheet"}, {"file", file.string()}}};
  const std::string message = errorOf(scene);
  EXPECT_NE(message.find("contact.obstacles[0].file: "), std::string::npos) << message;
  EXPECT_NE(message.find("is not closed: 3 open boundary edges"), std::string::npos) << message;
  EXPECT_NE(message.find("\"closed\": false"), std::string::npos) << message;
  scene["contact"]["obstacles"][0]["closed"] = false;
  EXPECT_EQ(errorOf(scene), "no error");
}

// Total momentum sum_i (M v)_i of the whole mesh, per axis.
Eigen::Vector3d momentum(const Simulation& simulation) {
  const Eigen::VectorXd mv = simulation.problem->massMatrix() * simulation.integrator->velocity();
  return mv.reshaped(3, mv.size() / 3).rowwise().sum();
}

TEST(SceneObjects, TwoBodiesCollidingHeadOnKeepMomentumAndSymmetry) {
  const double speed = 0.5;
  Simulation simulation = buildSimulation(parseScene(twoBoxes(0.1, speed), "", "s.json"));
  const int n = simulation.mesh->numVertices() / 2;
  const double mass = 1000.0;  // each box: 1 m^3 at 1000 kg/m^3
  EXPECT_NEAR(simulation.integrator->velocity()[0], speed, 0.0);
  double largestMomentum = 0.0;
  double largestAsymmetry = 0.0;
  for (int step = 0; step < 120; ++step) {
    const Eigen::Vector3d before = momentum(simulation);
    simulation.integrator->step();
    // Backward Euler changes the momentum by h times the sum of the forces: zero for the
    // elastic forces (rigid translations are in K's null space) and the contact pairs
    // (weights sum to zero), so the change per step is the round-off of the solve.
    largestMomentum = std::max(largestMomentum, (momentum(simulation) - before).norm());
    const Eigen::VectorXd& u = simulation.integrator->displacement();
    const Eigen::Matrix3Xd& rest = simulation.mesh->restPositions();
    for (int v = 0; v < n; ++v) {
      const Eigen::Vector3d left = rest.col(v) + u.segment<3>(3 * v);
      const Eigen::Vector3d right = rest.col(n + v) + u.segment<3>(3 * (n + v));
      largestAsymmetry = std::max(largestAsymmetry, (right - kTurn * left).norm());
    }
  }
  const SurfaceContactStats stats = simulation.contact->surfaces()->stats();
  EXPECT_GT(stats.activePairs, 0);  // they did touch
  // ... and bounced: the left box now moves left.
  double leftVelocity = 0.0;
  for (int v = 0; v < n; ++v) leftVelocity += simulation.integrator->velocity()[3 * v] / n;
  EXPECT_LT(leftVelocity, 0.0);
  // Round-off: 1e-12 of the momentum each box carries (mass * speed = 500), per step.
  EXPECT_LE(largestMomentum, 1e-12 * mass * speed);
  // Point symmetry to round-off grown over 120 steps (1e-12 of the box size).
  EXPECT_LE(largestAsymmetry, 1e-12);
}

// Two objects read from Vega's CUBIC cubes.veg (hexahedra, two materials, 750 kg each),
// 0.1 apart along x and offset in y so that their surface grids do not line up, moving at
// 0.5 m/s towards each other: one hexahedral mesh, surface contact between its two boundary
// surfaces (quads split into triangles), momentum kept to round-off and a rebound. An object
// of tetrahedra beside them is refused by name.
TEST(SceneObjects, HexahedralObjectsCollideAndKeepMomentum) {
  const std::string cubes = std::string(ASYNCFEM_TEST_DATA_DIR) + "/volumetricMesh/cubes.veg";
  json scene = json::parse(R"({
    "objects": [
      {"name": "left", "translation": [-1.05, 0, 0], "velocity": [0.5, 0, 0]},
      {"name": "right", "translation": [0.05, 0.13, 0], "velocity": [-0.5, 0, 0]}
    ],
    "contact": {"surfaces": {"thickness": 0.05}, "stiffness": 2e5},
    "integrator": {"name": "backward-euler", "timestep": 0.0016666666666666668},
    "frames": {"rate": 60, "count": 2}
  })");
  for (json& object : scene["objects"]) object["mesh"] = {{"file", cubes}};
  Simulation simulation = buildSimulation(parseScene(scene, "", "s.json"));
  ASSERT_TRUE(simulation.mesh->isHexahedral());
  EXPECT_EQ(simulation.mesh->numElements(), 8);
  EXPECT_EQ(simulation.mesh->elementSet("right").front(), 4);
  const int n = simulation.mesh->numVertices() / 2;
  const double mass = 750.0;  // cubes.veg: two cubes of 0.125 m^3 at 1000 and two at 2000 kg/m^3
  double largestMomentum = 0.0;
  for (int step = 0; step < 120; ++step) {
    const Eigen::Vector3d before = momentum(simulation);
    simulation.integrator->step();
    largestMomentum = std::max(largestMomentum, (momentum(simulation) - before).norm());
  }
  EXPECT_GT(simulation.contact->surfaces()->stats().activePairs, 0);  // they touched
  double leftVelocity = 0.0;
  for (int v = 0; v < n; ++v) leftVelocity += simulation.integrator->velocity()[3 * v] / n;
  EXPECT_LT(leftVelocity, 0.0);  // and bounced
  // As TwoBodiesCollidingHeadOnKeepMomentumAndSymmetry: round-off of the solve per step.
  EXPECT_LE(largestMomentum, 1e-12 * mass * 0.5);

  scene["objects"][1]["mesh"] = json::parse(R"({"generator": "box", "size": [1, 1, 0.5], "cells": [2, 2, 1]})");
  const std::string message = errorOf(scene);
  EXPECT_NE(message.find("objects[1].mesh: objects[1] 'right' has tetrahedra and objects[0] 'left' hexahedra"),
            std::string::npos)
      << message;
}

// models/collision/headOn.json with k = 5e4 (explicit contact's stable limit at the
// scene's step is near 5e3) and the given contact treatment and step, run to t = 0.1 s
// (the blocks touch from about 0.02 s to 0.08 s): the displacements at the end, and for
// implicit contact the largest relative residual over the steps that iterated and the
// run summary's implicit-contact line.
struct HeadOnRun {
  Eigen::VectorXd displacement;
  Eigen::VectorXd velocity;
  double largestResidual = 0.0;
  int contactSteps = 0;
  std::string summary;
};

HeadOnRun headOn(bool implicit, int stepsPerFrame) {
  json scene = json::parse(R"({
    "objects": [
      {"name": "left", "mesh": {"generator": "box", "size": [0.4, 0.3, 0.3], "cells": [8, 6, 6],
        "material": {"name": "rubber", "density": 1000, "youngsModulus": 2e5, "poissonRatio": 0.4}},
       "translation": [-0.43, -0.137, -0.15], "velocity": [1, 0, 0]},
      {"name": "right", "mesh": {"generator": "box", "size": [0.4, 0.3, 0.3], "cells": [8, 6, 6],
        "material": {"name": "rubber", "density": 1000, "youngsModulus": 2e5, "poissonRatio": 0.4}},
       "rotation": {"axis": [0, 1, 1], "angle": 180}, "translation": [0.43, -0.15, -0.137], "velocity": [-1, 0, 0]}
    ],
    "contact": {"surfaces": {"thickness": 0.02}, "stiffness": 5e4, "damping": 0},
    "mass": "consistent",
    "forceModel": {"type": "linear"},
    "integrator": {"name": "backward-euler"},
    "frames": {"rate": 60, "count": 6}
  })");
  scene["contact"]["implicit"] = implicit;
  scene["integrator"]["stepsPerFrame"] = stepsPerFrame;
  Simulation simulation = buildSimulation(parseScene(scene, "", "headOn.json"));
  const auto* integrator = dynamic_cast<const BackwardEuler*>(simulation.integrator.get());
  EXPECT_NE(integrator, nullptr);
  HeadOnRun run;
  for (int step = 0; step < 6 * stepsPerFrame; ++step) {
    simulation.integrator->step();
    if (integrator != nullptr && integrator->lastRelativeResidual() >= 0.0) {
      ++run.contactSteps;
      run.largestResidual = std::max(run.largestResidual, integrator->lastRelativeResidual());
    }
  }
  run.displacement = simulation.integrator->displacement();
  run.velocity = simulation.integrator->velocity();
  for (const std::string& line : simulation.integrator->report().lines)
    if (line.rfind("implicit contact", 0) == 0) run.summary = line;
  return run;
}

TEST(SceneObjects, ImplicitHeadOnCollisionConvergesEveryContactStep) {
  // At the scene's step (h = 1/480 s, h^2 k about 30 times a vertex's mass) the per-vertex
  // bounds of the pairs between the two bodies left 29 of 30 contact steps unconverged
  // (largest relative residual 0.17); the couplings' off-diagonal blocks make every one
  // converge to the tolerance (1e-8).
  const HeadOnRun run = headOn(true, 8);
  EXPECT_GT(run.contactSteps, 20);
  EXPECT_LE(run.largestResidual, 1e-8);
  EXPECT_NE(run.summary.find(", 0 steps stopped at"), std::string::npos) << run.summary;
  EXPECT_NE(run.summary.find("off-diagonal blocks (0 solves took"), std::string::npos) << run.summary;
}

TEST(SceneObjects, ImplicitHeadOnCollisionAgreesWithExplicitContact) {
  // The two treatments are backward Euler steps that differ only in where the contact
  // force is taken (the step's end or its start), by O(h) per contact; backward Euler
  // itself is first order too (its damping of the bounce). At h = 1/3840 s (explicit
  // contact stable: omega h about 0.3 for one vertex's pair) the left block's mean rebound
  // velocity and displacement must agree between them within a tenth of backward
  // Euler's own step error there, estimated by the implicit run's change from h = 1/1920 s
  // (measured: 0.04 and 0.03 of it; the rebound velocity itself changes by 0.024 m/s).
  const HeadOnRun coarse = headOn(true, 32);
  const HeadOnRun implicit = headOn(true, 64);
  const HeadOnRun explicitRun = headOn(false, 64);
  EXPECT_NE(coarse.summary.find(", 0 steps stopped at"), std::string::npos) << coarse.summary;
  EXPECT_NE(implicit.summary.find(", 0 steps stopped at"), std::string::npos) << implicit.summary;
  const auto leftMean = [](const Eigen::VectorXd& x) {
    const Eigen::Index n = x.size() / 6;  // the left block's vertices come first
    double sum = 0.0;
    for (Eigen::Index v = 0; v < n; ++v) sum += x[3 * v];
    return sum / static_cast<double>(n);
  };
  const double velocity = leftMean(implicit.velocity);
  EXPECT_LT(velocity, -0.5);  // bounced back (it came in at +1 m/s)
  const double velocityStepError = std::abs(velocity - leftMean(coarse.velocity));
  const double displacementStepError = std::abs(leftMean(implicit.displacement) - leftMean(coarse.displacement));
  EXPECT_LE(std::abs(velocity - leftMean(explicitRun.velocity)), 0.1 * velocityStepError);
  EXPECT_LE(std::abs(leftMean(implicit.displacement) - leftMean(explicitRun.displacement)),
            0.1 * displacementStepError);
}

}  // namespace
}  // namespace asyncfem

namespace asyncfem {
namespace {

// An icosphere of radius 1 about the origin, `level` times subdivided (20 * 4^level
// triangles), as OBJ text scaled by the obstacle's placement.
std::string icosphereObj(int level) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> vertices = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                           {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Eigen::Vector3i> faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                        {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                        {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                        {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (Eigen::Vector3d& v : vertices) v.normalize();
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> middle;
    const auto between = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto [it, added] = middle.try_emplace(key, static_cast<int>(vertices.size()));
      if (added)
        vertices.push_back(
            (vertices[static_cast<std::size_t>(a)] + vertices[static_cast<std::size_t>(b)]).normalized());
      return it->second;
    };
    std::vector<Eigen::Vector3i> finer;
    for (const Eigen::Vector3i& f : faces) {
      const int ab = between(f[0], f[1]), bc = between(f[1], f[2]), ca = between(f[2], f[0]);
      finer.insert(finer.end(), {{f[0], ab, ca}, {f[1], bc, ab}, {f[2], ca, bc}, {ab, bc, ca}});
    }
    faces = std::move(finer);
  }
  std::ostringstream obj;
  obj.precision(17);
  for (const Eigen::Vector3d& v : vertices) obj << "v " << v.x() << " " << v.y() << " " << v.z() << "\n";
  for (const Eigen::Vector3i& f : faces) obj << "f " << f[0] + 1 << " " << f[1] + 1 << " " << f[2] + 1 << "\n";
  return obj.str();
}

// A small light box (10 g: its weight, 0.1 N, far below what one pair of the layer holds,
// k dhat = 4 N), a corner down, dropped onto a sphere of radius 0.5 about the origin (off
// its top); the lowest corner's positions over 0.15 s.
constexpr int kSteps = 90;

std::vector<Eigen::Vector3d> cornerPath(const json& contact) {
  // The corner (0, 0, 0) at the bottom: the diagonal (1, 1, 1) turned onto +y.
  json scene = json::parse(R"({
    "objects": [{"name": "box", "mesh": {"generator": "box", "size": [0.1, 0.1, 0.1], "cells": [1, 1, 1],
                   "material": {"name": "m", "density": 10, "youngsModulus": 1e6, "poissonRatio": 0.3}},
                 "rotation": {"axis": [-1, 0, 1], "angle": 54.735610317245346},
                 "translation": [0.06, 0.515, 0.04]}],
    "gravity": [0, -9.81, 0],
    "integrator": {"name": "backward-euler", "timestep": 0.001},
    "frames": {"rate": 100, "count": 1}
  })");
  scene["contact"] = contact;
  Simulation simulation = buildSimulation(parseScene(scene, "", "sphere.json"));
  const Eigen::Matrix3Xd& rest = simulation.mesh->restPositions();
  Eigen::Index corner = 0;
  rest.row(1).minCoeff(&corner);
  std::vector<Eigen::Vector3d> path;
  for (int step = 0; step < kSteps; ++step) {
    simulation.integrator->step();
    path.emplace_back(rest.col(corner) + simulation.integrator->displacement().segment<3>(3 * corner));
  }
  return path;
}

TEST(MeshObstacles, AMeshSphereApproachesTheAnalyticSphereAsItIsRefined) {
  if (!surfaceReaderAvailable()) GTEST_SKIP() << "this build reads no surfaces (no assimp)";
  const test::ScratchFolder folder;
  const double thickness = 0.002;
  // The analytic sphere's law at depth r - |x - c| equals the mesh sphere's k (dhat - d)
  // with the exact distance d when r = 0.5 + dhat.
  const json analytic = {
      {"spheres", {{{"center", {0, 0, 0}}, {"radius", 0.5 + thickness}}}}, {"stiffness", 2000}, {"damping", 2}};
  const std::vector<Eigen::Vector3d> reference = cornerPath(analytic);
  std::vector<double> errors;
  for (int level = 1; level <= 5; ++level) {
    const std::filesystem::path file = folder.write("sphere" + std::to_string(level) + ".obj", icosphereObj(level));
    const json mesh = {{"obstacles", {{{"name", "sphere"}, {"file", file.string()}, {"scale", 0.5}}}},
                       {"surfaces", {{"thickness", thickness}, {"edges", false}}},
                       {"stiffness", 2000},
                       {"damping", 2}};
    const std::vector<Eigen::Vector3d> path = cornerPath(mesh);
    double largest = 0.0;
    for (std::size_t k = 0; k < path.size(); ++k) largest = std::max(largest, (path[k] - reference[k]).norm());
    errors.push_back(largest);
  }
  // The corner lands: it falls 0.02 and is held (not through the sphere).
  EXPECT_GT(reference.back().norm(), 0.49);
  // Each level halves the edge. The tessellation's facets lie inside the sphere by
  // O(edge^2) but their normals tilt from the radial direction by O(edge / R), which
  // steers the sliding corner: first order. The least-squares slope of log2(error)
  // against the level measured -1.3 (errors 0.029, 0.012, 0.0033, 0.0026, 0.00084 m; where
  // the corner lands within a facet makes single levels noisy); asked: below -0.75.
  double meanLevel = 0.0, meanLog = 0.0;
  for (std::size_t k = 0; k < errors.size(); ++k) {
    meanLevel += static_cast<double>(k) / static_cast<double>(errors.size());
    meanLog += std::log2(errors[k]) / static_cast<double>(errors.size());
  }
  double covariance = 0.0, variance = 0.0;
  for (std::size_t k = 0; k < errors.size(); ++k) {
    covariance += (static_cast<double>(k) - meanLevel) * (std::log2(errors[k]) - meanLog);
    variance += (static_cast<double>(k) - meanLevel) * (static_cast<double>(k) - meanLevel);
  }
  EXPECT_LT(covariance / variance, -0.75) << "errors " << errors[0] << " ... " << errors.back();
  EXPECT_LT(errors.back(), errors.front() / 8);
}

}  // namespace
}  // namespace asyncfem
