// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/multirateIntegrator.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <cmath>
#include <functional>
#include <sstream>
#include <vector>

#include "sceneTestUtilities.hpp"

namespace {

using asyncfem::Scene;
using asyncfem::Simulation;
using asyncfem::test::smallScene;

Simulation build(const nlohmann::json& json, const std::filesystem::path& base = "") {
  return asyncfem::buildSimulation(asyncfem::parseScene(json, base, "scene.json"));
}

// The frame timing of a scene (nothing is built); a timestep that does not divide the
// frame interval is reported here, where the timing is used.
asyncfem::FrameTiming timingOf(const nlohmann::json& json) {
  return asyncfem::requireFrameTiming(asyncfem::parseScene(json, "", "scene.json"));
}

// f_ext(t) of a built simulation at rest (size 3n; zero when it has no external force).
Eigen::VectorXd externalForce(const Simulation& simulation, double time) {
  const asyncfem::DynamicSystem& system = simulation.integrator->system();
  Eigen::VectorXd forces = Eigen::VectorXd::Zero(system.numDofs());
  if (system.externalForce) {
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(system.numDofs());
    system.externalForce(time, zero, zero, forces);
  }
  return forces;
}

bool contains(const std::vector<std::string>& list, const std::string& prefix) {
  return std::any_of(list.begin(), list.end(), [&](const std::string& s) { return s.rfind(prefix, 0) == 0; });
}

// Options belong to an integrator: switching an async scene to backward Euler drops (and
// names) the async-only keys, keeps the shared ones, and the scene then builds; switching
// back and forth with undeclared keys is covered by the registry's declared lists.
TEST(BuildSimulation, SwitchingIntegratorsDropsTheOptionsTheNewOneDoesNotRead) {
  nlohmann::json json = smallScene();
  json["integrator"] = nlohmann::json::parse(R"({"name": "async", "timestep": 0.01, "options": {
      "coupling": "paper", "schur": "lu",
      "regions": [{"name": "tip", "ratio": 4, "vertexSets": ["xmax"]}]}})");
  Scene scene = asyncfem::parseScene(json, "", "scene.json");
  const asyncfem::IntegratorRegistry registry = asyncfem::defaultIntegratorRegistry();
  Scene same = scene;
  EXPECT_TRUE(asyncfem::switchIntegrator(same, registry, "async").empty());
  EXPECT_EQ(same.integrator.options.size(), 3U);
  const std::vector<std::string> dropped = asyncfem::switchIntegrator(scene, registry, "backward-euler");
  EXPECT_EQ(dropped, (std::vector<std::string>{"coupling", "regions", "schur"}));
  EXPECT_EQ(scene.integrator.name, "backward-euler");
  EXPECT_TRUE(scene.integrator.options.empty());
  const Simulation simulation = asyncfem::buildSimulation(scene);
  EXPECT_EQ(simulation.integrator->name(), "backward-euler");
  // A shared key carries over: "solver" is read by every single-rate integrator.
  Scene single = asyncfem::parseScene(smallScene(), "", "scene.json");
  single.integrator.options = nlohmann::json::parse(R"({"solver": "umfpack", "maxIterations": 3})");
  EXPECT_TRUE(asyncfem::switchIntegrator(single, registry, "trapezoidal").empty());
  EXPECT_EQ(single.integrator.options.size(), 2U);
  EXPECT_EQ(asyncfem::switchIntegrator(single, registry, "async"),
            (std::vector<std::string>{"maxIterations", "solver"}));
}

TEST(BuildSimulation, GeneratorMeshAndTiming) {
  const Simulation simulation = build(smallScene());
  EXPECT_EQ(simulation.mesh->numVertices(), 12);
  EXPECT_EQ(simulation.timing.timestep, 0.01);
  EXPECT_EQ(simulation.integrator->timestep(), 0.01);
  EXPECT_DOUBLE_EQ(simulation.timing.frameInterval, 0.1);
  EXPECT_EQ(simulation.timing.stepsPerFrame, 10);
  EXPECT_EQ(simulation.timing.frameCount, 3);
  EXPECT_EQ(simulation.integrator->name(), "backward-euler");
  EXPECT_DOUBLE_EQ(simulation.monitor->boundingBoxDiagonal(), std::sqrt(6.0));
  EXPECT_DOUBLE_EQ(simulation.monitor->blowUpDisplacement(), 1000.0 * std::sqrt(6.0));
}

TEST(BuildSimulation, StepsPerFrameToleratesRounding) {
  auto json = smallScene();
  json["frames"]["rate"] = 30;
  json["integrator"]["timestep"] = 1.0 / 300.0;
  EXPECT_EQ(timingOf(json).stepsPerFrame, 10);
  json["integrator"]["timestep"] = 1.0 / 290.0;
  try {
    (void)timingOf(json);
    FAIL() << "expected a timing error";
  } catch (const asyncfem::ValidationError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("integrator.timestep"), std::string::npos) << message;
    EXPECT_NE(message.find("frames.rate"), std::string::npos) << message;
  }
}

TEST(BuildSimulation, StepsPerFrameGivesTheTimestep) {
  auto json = smallScene();
  json["integrator"].erase("timestep");
  json["integrator"]["stepsPerFrame"] = 4;
  const Scene scene = asyncfem::parseScene(json, "", "scene.json");
  EXPECT_EQ(scene.timing.timestep, 0.1 / 4);  // known before the build, for utilities
  EXPECT_EQ(scene.timing.stepsPerFrame, 4);
  const Simulation simulation = asyncfem::buildSimulation(scene);
  EXPECT_EQ(simulation.timing, scene.timing);
  EXPECT_EQ(simulation.integrator->timestep(), 0.1 / 4);
}

asyncfem::TimingOverrides overrides(std::optional<double> timestep, std::optional<int> stepsPerFrame,
                                    std::optional<int> frameCount) {
  asyncfem::TimingOverrides result;
  result.timestep = timestep;
  result.stepsPerFrame = stepsPerFrame;
  result.frameCount = frameCount;
  return result;
}

// Command-line values go through overrideFrameTiming, which resolves the timing again
// with the scene's errors; buildSimulation then runs with it.
TEST(BuildSimulation, TimingOverridesAreResolvedAgain) {
  Scene scene = asyncfem::parseScene(smallScene(), "", "scene.json");  // rate 10, h 0.01, 3 frames
  asyncfem::overrideFrameTiming(scene, overrides({}, 5, 7));
  EXPECT_EQ(scene.timing.timestep, 0.1 / 5);
  EXPECT_EQ(scene.timing.frameCount, 7);
  asyncfem::overrideFrameTiming(scene, overrides(0.025, {}, {}));
  EXPECT_EQ(scene.timing.stepsPerFrame, 4);
  EXPECT_EQ(scene.timing.frameCount, 7);
  EXPECT_EQ(asyncfem::buildSimulation(scene).integrator->timestep(), 0.025);
  const asyncfem::FrameTiming before = scene.timing;
  try {
    asyncfem::overrideFrameTiming(scene, overrides(0.03, {}, {}));
    FAIL() << "expected a timing error";
  } catch (const asyncfem::ValidationError& error) {
    EXPECT_EQ(std::string(error.what()).rfind("scene.json: integrator.timestep: 0.03 does not divide", 0), 0U)
        << error.what();
  }
  EXPECT_THROW(asyncfem::overrideFrameTiming(scene, overrides({}, {}, 0)), asyncfem::ValidationError);
  EXPECT_THROW(asyncfem::overrideFrameTiming(scene, overrides(0.02, 5, {})), asyncfem::ValidationError);
  EXPECT_EQ(scene.timing, before);  // a refused override leaves the timing as it was
}

// An override of the frame count or rate keeps the timestep as it was given, bit for bit
// (the timing is not rebuilt from its steps per frame, which would round it to T / N).
TEST(BuildSimulation, TimingOverridesKeepTheGivenTimestep) {
  auto json = smallScene();
  json["frames"]["rate"] = 30;
  json["integrator"]["timestep"] = 0.001010101010;  // 1/990 to ten significant digits: 33 per frame
  Scene scene = asyncfem::parseScene(json, "", "scene.json");
  ASSERT_EQ(scene.timing.stepsPerFrame, 33);
  ASSERT_NE(scene.timing.timestep, scene.timing.frameInterval / 33);  // the rounding the test guards against
  asyncfem::overrideFrameTiming(scene, {.frameCount = 5});
  EXPECT_EQ(scene.timing.timestep, 0.001010101010);
  EXPECT_EQ(scene.timing.stepsPerFrame, 33);
  EXPECT_EQ(scene.timing.frameCount, 5);
  asyncfem::overrideFrameTiming(scene, {.frameRate = 30.0 / 11});  // one frame is 11 of the old ones
  EXPECT_EQ(scene.timing.timestep, 0.001010101010);
  EXPECT_EQ(scene.timing.stepsPerFrame, 363);
  EXPECT_EQ(scene.timing.frameRate, 30.0 / 11);
}

// A timestep that does not divide the frame interval leaves the scene readable (its mesh,
// its timing as written, not resolved); running it is refused with the timing error, and
// an override of the step resolves it.
TEST(BuildSimulation, UnresolvedTimingIsReportedWhenUsed) {
  auto json = smallScene();  // rate 10, 3 frames
  json["integrator"]["timestep"] = 0.03;
  Scene scene = asyncfem::parseScene(json, "", "scene.json");
  EXPECT_FALSE(scene.timing.resolved());
  EXPECT_EQ(scene.timing.timestep, 0.03);
  EXPECT_EQ(scene.timing.frameRate, 10.0);
  EXPECT_EQ(scene.timing.frameCount, 3);
  for (const auto& use : std::vector<std::function<void()>>{[&] { (void)asyncfem::requireFrameTiming(scene); },
                                                            [&] { (void)asyncfem::buildSimulation(scene); },
                                                            [&] { (void)asyncfem::integratorContext(scene); }}) {
    try {
      use();
      ADD_FAILURE() << "expected a timing error";
    } catch (const asyncfem::ValidationError& error) {
      EXPECT_EQ(std::string(error.what()).rfind("scene.json: integrator.timestep: 0.03 does not divide", 0), 0U)
          << error.what();
    }
  }
  asyncfem::overrideFrameTiming(scene, {.stepsPerFrame = 2});
  EXPECT_TRUE(scene.timing.resolved());
  EXPECT_EQ(asyncfem::buildSimulation(scene).integrator->timestep(), 0.05);
}

// A timestep within a relative 1e-9 (timestepDivisorTolerance) of a divisor T / N of the
// frame interval runs N steps per frame; further away it is refused, with the two nearest
// divisors in the message.
TEST(BuildSimulation, TimestepWithinRoundOffOfADivisorIsAccepted) {
  auto json = smallScene();
  json["frames"]["rate"] = 30;
  json["integrator"]["timestep"] = (1.0 / 990.0) * (1.0 + 5e-10);
  EXPECT_EQ(timingOf(json).stepsPerFrame, 33);
  json["integrator"]["timestep"] = 0.001010101010;  // 1/990 to ten significant digits
  EXPECT_EQ(timingOf(json).stepsPerFrame, 33);
  json["integrator"]["timestep"] = (1.0 / 990.0) * (1.0 + 2e-9);
  EXPECT_THROW((void)timingOf(json), asyncfem::ValidationError);
  json["integrator"]["timestep"] = 0.001;
  try {
    (void)timingOf(json);
    FAIL() << "expected a timing error";
  } catch (const asyncfem::ValidationError& error) {
    EXPECT_EQ(std::string(error.what()),
              "scene.json: integrator.timestep: 0.001 does not divide the frame interval 1/30 s (frames.rate 30) "
              "into whole steps: 33.3333333333 steps per frame; the nearest valid timesteps are 1/990 s = "
              "0.00101010101 s (33 steps per frame) and 1/1020 s = 0.000980392157 s (34 steps per frame); or give "
              "the steps per frame instead (integrator.stepsPerFrame)");
  }
}

// Steps whose load evaluations see a non-zero pull: a window [a, b) acts at the step
// times t = k h with a <= t < b, a step time within 1e-9 h of b counting as b. Step times
// are k h (not accumulated), so [0, 0.3] at h = 0.03 and [0, 0.1] at h = 0.01 (where
// summing h ten times lands above and below b) both hold exactly ten step times: t_0 ..
// t_9. Backward Euler evaluates f_ext at step ends t_1 .. t_9 (9 steps), symplectic Euler
// at step starts t_0 .. t_9 (10 steps).
int pulledSteps(const std::string& integrator, double windowEnd, double h) {
  int pulled = 0;
  asyncfem::IntegratorRegistry registry = asyncfem::defaultIntegratorRegistry();
  registry.add("counting", [&pulled, integrator](asyncfem::IntegratorContext context, const nlohmann::json& options) {
    context.system.externalForce = [&pulled, load = context.system.externalForce](double time, const Eigen::VectorXd& u,
                                                                                  const Eigen::VectorXd& v,
                                                                                  Eigen::VectorXd& forces) {
      load(time, u, v, forces);
      pulled += forces.isZero(0.0) ? 0 : 1;
    };
    return asyncfem::defaultIntegratorRegistry().create(integrator, std::move(context), options);
  });
  auto json = smallScene();
  json["integrator"] = {{"name", "counting"}, {"stepsPerFrame", 1}, {"options", {{"force", true}}}};
  json["frames"]["rate"] = 1.0 / h;
  json["forces"] = {{{"type", "pull"}, {"set", "xmax"}, {"force", {0, -1, 0}}, {"window", {0.0, windowEnd}}}};
  const Simulation simulation = asyncfem::buildSimulation(asyncfem::parseScene(json, "", "scene.json"), registry);
  for (int k = 0; k < 20; ++k) simulation.integrator->step();
  return pulled;
}

TEST(BuildSimulation, PullWindowEndingOnAStepTimeHoldsTheSameStepsWhateverTheRoundOff) {
  EXPECT_EQ(pulledSteps("backward-euler", 0.3, 0.03), 9);
  EXPECT_EQ(pulledSteps("backward-euler", 0.1, 0.01), 9);
  EXPECT_EQ(pulledSteps("symplectic-euler", 0.3, 0.03), 10);
  EXPECT_EQ(pulledSteps("symplectic-euler", 0.1, 0.01), 10);
}

TEST(BuildSimulation, FileMeshMatchesTheGenerator) {
  const asyncfem::test::ScratchFolder folder;
  asyncfem::BoxMeshSpec spec;
  spec.size = Eigen::Vector3d(2, 1, 1);
  spec.cells = Eigen::Vector3i(2, 1, 1);
  spec.material = asyncfem::Material{"rubber", 1000, 1e5, 0.4};
  std::filesystem::create_directories(folder.path() / "meshes");
  asyncfem::writeVeg(folder.path() / "meshes/box.veg", makeBoxMesh(spec));
  auto json = smallScene();
  json["mesh"] = {{"file", "meshes/box.veg"}};
  const Simulation fromFile = build(json, folder.path());
  const Simulation generated = build(smallScene());
  EXPECT_EQ(fromFile.mesh->numVertices(), generated.mesh->numVertices());
  EXPECT_EQ(fromFile.mesh->restPositions(), generated.mesh->restPositions());
  EXPECT_EQ(fromFile.fixedVertices, generated.fixedVertices);
  const Eigen::MatrixXd massDifference =
      Eigen::MatrixXd(fromFile.integrator->system().mass) - Eigen::MatrixXd(generated.integrator->system().mass);
  EXPECT_LE(massDifference.cwiseAbs().maxCoeff(), 1e-12);
}

// The mesh of smallScene(): a 2 x 1 x 1 box of 2 x 1 x 1 cells, for writing in other formats.
asyncfem::TetMesh smallBox() {
  asyncfem::BoxMeshSpec spec;
  spec.size = Eigen::Vector3d(2, 1, 1);
  spec.cells = Eigen::Vector3i(2, 1, 1);
  return makeBoxMesh(spec);
}

// A TetGen mesh with a stray vertex that no tetrahedron uses (as Gmsh and TetGen files with
// a leftover surface have): the scene runs, the stray vertex stays at rest, and every
// reader warning reaches Simulation::warnings with the scene key and the file.
TEST(BuildSimulation, VertexInNoElementIsHeldAndTheReaderWarningsArrive) {
  const asyncfem::test::ScratchFolder folder;
  const asyncfem::TetMesh box = smallBox();
  std::ostringstream node;
  node << box.numVertices() + 1 << " 3 0 0\n";
  for (int v = 0; v < box.numVertices(); ++v) {
    node << v + 1 << ' ' << box.restPosition(v).transpose() << '\n';
  }
  node << box.numVertices() + 1 << " 5 5 5\n";
  std::ostringstream ele;
  ele << box.numElements() << " 4 0\n";
  for (int e = 0; e < box.numElements(); ++e) ele << e + 1 << ' ' << (box.element(e).array() + 1).transpose() << '\n';
  folder.write("box.node", node.str());
  folder.write("box.ele", ele.str());
  auto json = smallScene();
  json["mesh"] = {{"file", "box.node"}};
  json["fixed"] = nlohmann::json::parse(R"({"boxes": [{"min": [-0.1, -1, -1], "max": [0.1, 2, 2]}]})");
  json["gravity"] = {0, -9.81, 0};
  Simulation simulation = build(json, folder.path());
  const int stray = box.numVertices();
  EXPECT_EQ(simulation.problem->unusedVertices(), std::vector<int>{stray});
  EXPECT_EQ(simulation.fixedVertices.size(), 4U);  // the unused vertex is held, not fixed
  EXPECT_EQ(simulation.integrator->system().freeDofs.numFree(), 3 * (box.numVertices() - 4));
  const std::string prefix = "scene.json: mesh.file: " + (folder.path() / "box.node").string() + ": ";
  EXPECT_TRUE(contains(simulation.warnings,
                       prefix + "1 vertex(es) belong to no element (first: vertex " + std::to_string(stray + 1) + ")"))
      << ::testing::PrintToString(simulation.warnings);
  EXPECT_TRUE(contains(simulation.warnings, prefix + "the file has no materials"))
      << ::testing::PrintToString(simulation.warnings);
  asyncfem::advanceFrame(simulation, 0);  // before: "cholmod: matrix is not positive definite"
  const Eigen::VectorXd& u = simulation.integrator->displacement();
  EXPECT_TRUE(u.segment<3>(3 * stray).isZero(0.0));
  EXPECT_LT(u[(3 * box.vertexSet("xmax")[0]) + 1], 0.0);  // the free end sags
}

// A boundary tagged in Gmsh as the physical surface "root" fixes its vertices by name.
TEST(BuildSimulation, GmshPhysicalSurfaceFixesByName) {
  const asyncfem::test::ScratchFolder folder;
  const asyncfem::TetMesh box = smallBox();
  std::vector<std::array<int, 3>> rootTriangles;
  for (const std::array<int, 3>& triangle : asyncfem::boundaryTriangles(box)) {
    if (std::all_of(triangle.begin(), triangle.end(), [&](int v) { return box.restPosition(v).x() == 0.0; })) {
      rootTriangles.push_back(triangle);
    }
  }
  std::ostringstream msh;
  msh << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n2 1 \"root\"\n$EndPhysicalNames\n$Nodes\n"
      << box.numVertices() << '\n';
  for (int v = 0; v < box.numVertices(); ++v) msh << v + 1 << ' ' << box.restPosition(v).transpose() << '\n';
  msh << "$EndNodes\n$Elements\n" << rootTriangles.size() + static_cast<std::size_t>(box.numElements()) << '\n';
  int tag = 1;
  for (const std::array<int, 3>& t : rootTriangles) {
    msh << tag++ << " 2 2 1 1 " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  }
  for (int e = 0; e < box.numElements(); ++e) {
    msh << tag++ << " 4 2 0 1 " << (box.element(e).array() + 1).transpose() << '\n';
  }
  msh << "$EndElements\n";
  folder.write("box.msh", msh.str());
  auto json = smallScene();
  json["mesh"] = {{"file", "box.msh"}};
  json["fixed"] = {{"sets", {"root"}}};
  const Simulation simulation = build(json, folder.path());
  EXPECT_EQ(simulation.fixedVertices, box.vertexSet("xmin"));
}

// An explicit step above the stable limit: the message says which steps per frame work,
// and they do (one fewer does not).
TEST(BuildSimulation, UnstableExplicitStepNamesTheStepsPerFrameThatWork) {
  auto json = smallScene();
  json["mesh"]["material"]["youngsModulus"] = 1e8;
  json["integrator"]["name"] = "central-differences";
  std::string message;
  try {
    (void)build(json);
  } catch (const asyncfem::TimestepError& error) {
    message = error.what();
  }
  const std::string key = "at frames.rate 10 the stable steps per frame are ";
  const std::size_t at = message.find(key);
  ASSERT_NE(at, std::string::npos) << message;
  const int steps = std::stoi(message.substr(at + key.size()));
  EXPECT_NE(message.find(std::to_string(steps) + " or more (integrator.stepsPerFrame: " + std::to_string(steps) +
                         " gives a timestep of "),
            std::string::npos)
      << message;
  json["integrator"].erase("timestep");
  json["integrator"]["stepsPerFrame"] = steps;
  EXPECT_NO_THROW((void)build(json));
  json["integrator"]["stepsPerFrame"] = steps - 1;
  EXPECT_THROW((void)build(json), asyncfem::TimestepError);
}

TEST(BuildSimulation, FixedBySetBoxAndBou) {
  const asyncfem::test::ScratchFolder folder;
  const Simulation bySet = build(smallScene());
  ASSERT_EQ(bySet.fixedVertices.size(), 4U);  // the x = 0 face of a 2 x 1 x 1 cell box
  for (const int v : bySet.fixedVertices) {
    EXPECT_EQ(bySet.mesh->restPosition(v).x(), 0.0);
  }
  EXPECT_EQ(bySet.integrator->system().freeDofs.numFixed(), 12);

  auto json = smallScene();
  json["fixed"] = nlohmann::json::parse(R"({"boxes": [{"min": [-0.1, -0.1, -0.1], "max": [0.1, 1.1, 1.1]}]})");
  EXPECT_EQ(build(json).fixedVertices, bySet.fixedVertices);

  folder.write("fixed.bou", "# 1-based, Vega style\n1, 2,\n3\n");
  json["fixed"] = nlohmann::json::parse(R"({"bou": "fixed.bou"})");
  EXPECT_EQ(build(json, folder.path()).fixedVertices, (std::vector<int>{0, 1, 2}));

  // The union of all three, without duplicates.
  json["fixed"] = nlohmann::json::parse(R"({"sets": ["xmin"], "bou": "fixed.bou",
                                           "boxes": [{"min": [1.9, -1, -1], "max": [2.1, 2, 2]}]})");
  const Simulation all = build(json, folder.path());
  EXPECT_EQ(all.fixedVertices.size(), 9U);  // 4 + 4 + the one .bou vertex (1) on neither face
  EXPECT_TRUE(std::is_sorted(all.fixedVertices.begin(), all.fixedVertices.end()));

  folder.write("bad.bou", "1, 2\n99\n");
  json["fixed"] = nlohmann::json::parse(R"({"bou": "bad.bou"})");
  try {
    (void)build(json, folder.path());
    FAIL() << "expected an error";
  } catch (const asyncfem::Error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("scene.json: fixed.bou: "), std::string::npos) << message;
    EXPECT_NE(message.find("bad.bou:2"), std::string::npos) << message;
  }
}

TEST(BuildSimulation, GravityAddsMassTimesG) {
  for (const char* mass : {"consistent", "lumped"}) {
    auto json = smallScene();
    json["gravity"] = {0.5, -9.81, 2.0};
    json["mass"] = mass;
    const Simulation simulation = build(json);
    const Eigen::Vector3d g(0.5, -9.81, 2.0);
    const Eigen::VectorXd stacked = g.replicate(simulation.mesh->numVertices(), 1);
    const Eigen::VectorXd expected = simulation.integrator->system().mass * stacked;
    const Eigen::VectorXd actual = externalForce(simulation, 0.37);
    EXPECT_LE((actual - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff()) << mass;
    // Total force = total mass * g (2 m^3 of density 1000).
    const double totalMass = asyncfem::totalMass(*simulation.mesh);
    EXPECT_NEAR(totalMass, 2000.0, 1e-9);
    for (int c = 0; c < 3; ++c) {
      double sum = 0.0;
      for (int v = 0; v < simulation.mesh->numVertices(); ++v) sum += actual[(3 * v) + c];
      EXPECT_NEAR(sum, totalMass * g[c], 1e-9 * totalMass * 10.0) << mass << " component " << c;
    }
  }
  const Simulation still = build(smallScene());
  EXPECT_FALSE(still.integrator->system().externalForce);
  EXPECT_TRUE(contains(still.skipped, "gravity load"));
  EXPECT_TRUE(contains(still.skipped, "external force evaluation"));
}

TEST(BuildSimulation, PullIsOnOnlyInsideItsWindow) {
  auto json = smallScene();
  json["forces"] =
      nlohmann::json::parse(R"([{"type": "pull", "set": "xmax", "force": [0, -8, 0], "window": [0.1, 0.2]}])");
  const Simulation simulation = build(json);
  const std::vector<int>& pulled = simulation.mesh->vertexSet("xmax");
  ASSERT_EQ(pulled.size(), 4U);
  EXPECT_TRUE(externalForce(simulation, 0.05).isZero(0.0));
  EXPECT_TRUE(externalForce(simulation, 0.2).isZero(0.0));  // the window is [start, end)
  EXPECT_TRUE(externalForce(simulation, 0.25).isZero(0.0));
  for (const double t : {0.1, 0.15, 0.1999}) {
    const Eigen::VectorXd f = externalForce(simulation, t);
    Eigen::VectorXd expected = Eigen::VectorXd::Zero(f.size());
    for (const int v : pulled) expected[(3 * v) + 1] = -2.0;  // -8 split over 4 vertices
    EXPECT_EQ(f, expected) << "t = " << t;
  }
}

TEST(BuildSimulation, PullOnExplicitVertices) {
  auto json = smallScene();
  json["forces"] = nlohmann::json::parse(R"([{"type": "pull", "vertices": [5, 7, 5], "force": [4, 0, 0]}])");
  const Eigen::VectorXd f = externalForce(build(json), 123.0);
  EXPECT_EQ(f[15], 2.0);  // duplicates count once: 4 split over vertices 5 and 7
  EXPECT_EQ(f[21], 2.0);
  EXPECT_EQ(f.sum(), 4.0);
}

TEST(BuildSimulation, ImpulseIsDeliveredOnceWhateverTheEvaluationTimes) {
  auto json = smallScene();
  json["forces"] = nlohmann::json::parse(R"([{"type": "impulse", "set": "xmax", "impulse": [0, 0, 3], "time": 0.05}])");
  const Simulation simulation = build(json);
  const double h = simulation.integrator->timestep();
  // Integrators evaluate f_ext at step starts (k h), step ends ((k + 1) h) or average both.
  double delivered = 0.0;
  int activeSteps = 0;
  for (int k = 0; k <= 20; ++k) {
    const Eigen::VectorXd f = externalForce(simulation, k * h);
    delivered += h * f.sum();
    activeSteps += f.isZero(0.0) ? 0 : 1;
  }
  EXPECT_NEAR(delivered, 3.0, 1e-12);
  EXPECT_EQ(activeSteps, 1);
}

TEST(BuildSimulation, MaterialOverridesPerSet) {
  auto json = smallScene();
  json["mesh"]["regions"] = nlohmann::json::parse(
      R"([{"name": "right", "min": [1, -1, -1], "max": [3, 2, 2],
           "material": {"name": "hard", "density": 500, "youngsModulus": 1e7, "poissonRatio": 0.3}}])");
  // "right" is the only user of "hard": changed in place. "allElements" also covers
  // "rubber" elements, so only their copy changes.
  json["materials"] =
      nlohmann::json::parse(R"([{"set": "right", "youngsModulus": 2e7}, {"set": "allElements", "density": 10}])");
  const Simulation simulation = build(json);
  const asyncfem::TetMesh& mesh = *simulation.mesh;
  const int hard = mesh.findMaterial("hard");
  const int rubber = mesh.findMaterial("rubber");
  ASSERT_GE(hard, 0);
  ASSERT_GE(rubber, 0);
  EXPECT_EQ(mesh.materials()[static_cast<std::size_t>(hard)], (asyncfem::Material{"hard", 10, 2e7, 0.3}));
  EXPECT_EQ(mesh.materials()[static_cast<std::size_t>(rubber)], (asyncfem::Material{"rubber", 10, 1e5, 0.4}));

  // A set covering part of a material's elements gets a copy named "<material>@<set>".
  const asyncfem::test::ScratchFolder folder;
  asyncfem::TetMesh box = *build(smallScene()).mesh;
  box.setElementSet("pair", {0, 1});
  asyncfem::writeVeg(folder.path() / "box.veg", box);
  json = smallScene();
  json["mesh"] = {{"file", "box.veg"}};
  json["materials"] = nlohmann::json::parse(R"([{"set": "pair", "poissonRatio": 0.1}, {"set": "pair", "density": 7}])");
  const Simulation partial = build(json, folder.path());
  const int copy = partial.mesh->findMaterial("rubber@pair");
  ASSERT_GE(copy, 0);
  EXPECT_EQ(partial.mesh->materials()[static_cast<std::size_t>(copy)],
            (asyncfem::Material{"rubber@pair", 7, 1e5, 0.1}));
  for (int e = 0; e < partial.mesh->numElements(); ++e) {
    EXPECT_EQ(partial.mesh->elementMaterial(e).name, e < 2 ? "rubber@pair" : "rubber") << "element " << e;
  }
}

// A Vega mesh carries element sets only: a pull, a fixed set and an async region may name
// one, and mean the vertices of its elements.
TEST(BuildSimulation, ElementSetsServeWhereVertexSetsDo) {
  const asyncfem::test::ScratchFolder folder;
  asyncfem::TetMesh box = *build(smallScene()).mesh;
  box.setElementSet("shell", {box.numElements() - 1});
  box.setElementSet("foot", {0});
  asyncfem::writeVeg(folder.path() / "box.veg", box);
  nlohmann::json json = smallScene();
  json["mesh"] = {{"file", "box.veg"}};
  json["fixed"] = {{"sets", {"foot"}}};
  json["forces"] = nlohmann::json::parse(R"([{"type": "pull", "set": "shell", "force": [0, -8, 0]}])");
  const Simulation simulation = build(json, folder.path());
  const std::vector<int> shell = simulation.mesh->setVertices("shell");
  ASSERT_EQ(shell.size(), 4U);
  const Eigen::VectorXd force = externalForce(*&simulation, 0.05);
  double total = 0.0;
  for (const int v : shell) total += force[3 * v + 1];
  EXPECT_NEAR(total, -8.0, 1e-12);
  const std::vector<int> foot = simulation.mesh->setVertices("foot");
  for (const int v : foot)
    EXPECT_TRUE(std::binary_search(simulation.fixedVertices.begin(), simulation.fixedVertices.end(), v));
}

TEST(BuildSimulation, BuildsOnlyWhatTheSceneUses) {
  const Simulation linear = build(smallScene());
  EXPECT_TRUE(linear.integrator->system().forceModel->isLinear());
  EXPECT_TRUE(contains(linear.skipped, "corotational"));
  EXPECT_TRUE(contains(linear.skipped, "vtu output"));
  EXPECT_TRUE(contains(linear.skipped, "velocity output"));
  EXPECT_TRUE(contains(linear.integrator->stats().skipped, "damping matrix"));
  EXPECT_TRUE(contains(linear.integrator->stats().skipped, "refactorization"));

  auto json = smallScene();
  json["forceModel"] = {{"type", "corotational"}, {"tangent", "exact"}};
  json["damping"] = {{"alpha", 0.1}, {"beta", 0.01}};
  json["output"] = nlohmann::json::parse(R"({"vtu": {"folder": "v"}, "velocities": true})");
  const Simulation corotational = build(json);
  EXPECT_FALSE(corotational.integrator->system().forceModel->isLinear());
  EXPECT_FALSE(contains(corotational.skipped, "corotational"));
  EXPECT_FALSE(contains(corotational.skipped, "vtu output"));
  EXPECT_FALSE(contains(corotational.skipped, "velocity output"));
  EXPECT_FALSE(contains(corotational.integrator->stats().skipped, "damping matrix"));
  EXPECT_EQ(corotational.integrator->system().rayleighMass, 0.1);
  EXPECT_EQ(corotational.integrator->system().rayleighStiffness, 0.01);
}

TEST(BuildSimulation, SingleRateOptionsReachTheIntegrator) {
  auto json = smallScene();
  json["integrator"] = nlohmann::json::parse(
      R"({"name": "symplectic-euler", "timestep": 0.001, "options": {"solver": "eigen-ldlt", "maxFrequency": 100}})");
  const Simulation simulation = build(json);
  EXPECT_EQ(simulation.integrator->name(), "symplectic-euler");
  EXPECT_DOUBLE_EQ(simulation.integrator->stableTimestepEstimate(), 2.0 / 100.0);
}

TEST(BuildSimulation, RegistryAcceptsOtherIntegrators) {
  asyncfem::IntegratorRegistry registry = asyncfem::defaultIntegratorRegistry();
  bool called = false;
  registry.add("custom", [&called](asyncfem::IntegratorContext context, const nlohmann::json& options) {
    called = true;
    EXPECT_EQ(context.mesh->numVertices(), 12);
    EXPECT_EQ(options.at("regions").size(), 2U);
    return asyncfem::defaultIntegratorRegistry().create("backward-euler", std::move(context), nlohmann::json::object());
  });
  auto json = smallScene();
  json["integrator"]["name"] = "custom";
  json["integrator"]["options"] = {{"regions", {1, 2}}};
  const Simulation simulation = asyncfem::buildSimulation(asyncfem::parseScene(json, "", "scene.json"), registry);
  EXPECT_TRUE(called);
  EXPECT_NE(registry.find("backward-euler"), nullptr);
}

TEST(AdvanceFrame, PulledBeamMovesAndReturns) {
  auto json = smallScene();
  json["forces"] =
      nlohmann::json::parse(R"([{"type": "pull", "set": "xmax", "force": [0, -100, 0], "window": [0, 0.1]}])");
  json["frames"]["count"] = 5;
  Simulation simulation = build(json);
  double previousTip = 0.0;
  for (int frame = 0; frame < simulation.timing.frameCount; ++frame) {
    asyncfem::advanceFrame(simulation, frame);
    EXPECT_NEAR(simulation.integrator->time(), (frame + 1) * 0.1, 1e-12);
    const double tip = simulation.integrator->displacement()[(3 * simulation.mesh->vertexSet("xmax")[0]) + 1];
    if (frame == 0) {
      EXPECT_LT(tip, 0.0);  // pulled down during the first frame
    }
    previousTip = tip;
  }
  EXPECT_TRUE(std::isfinite(previousTip));
  for (const int v : simulation.fixedVertices) {
    EXPECT_TRUE(simulation.integrator->displacement().segment<3>(3 * v).isZero(0.0));
  }
}

TEST(AdvanceFrame, UnstableExplicitRunNamesTheFrame) {
  auto json = smallScene();
  json["mesh"]["material"]["youngsModulus"] = 1e8;
  json["forces"] = nlohmann::json::parse(R"([{"type": "pull", "set": "xmax", "force": [0, -100, 0]}])");
  json["integrator"] =
      nlohmann::json::parse(R"({"name": "central-differences", "timestep": 0.01, "options": {"force": true}})");
  json["frames"]["count"] = 50;
  Simulation simulation = build(json);
  try {
    for (int frame = 0; frame < simulation.timing.frameCount; ++frame) {
      asyncfem::advanceFrame(simulation, frame);
    }
    FAIL() << "expected the forced explicit run to blow up";
  } catch (const asyncfem::NumericalError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.rfind("frame ", 0), 0U) << message;
    EXPECT_NE(message.find("unstable"), std::string::npos) << message;
  }
}

}  // namespace

namespace {

std::string sceneError(const nlohmann::json& json) {
  try {
    build(json);
  } catch (const asyncfem::Error& error) {
    return error.what();
  }
  return "no error";
}

// forceModel.type names the hyperelastic materials too: the scene runs them with Newton
// iterations (line search on by default) and they sag under gravity like the linear
// model at small strain; their keys are refused on the other models.
TEST(BuildSimulation, HyperelasticForceModelsRunFromTheScene) {
  auto json = smallScene();
  json["gravity"] = {0, -9.81, 0};
  json["integrator"]["options"] = {{"maxIterations", 5}, {"tolerance", 1e-8}};
  Simulation linear = build(json);
  for (int k = 0; k < 10; ++k) linear.integrator->step();
  for (const char* type : {"stvk", "neo-hookean"}) {
    json["forceModel"] = {{"type", type}};
    if (std::string(type) == "neo-hookean") json["forceModel"]["inversionThreshold"] = 0.2;
    Simulation simulation = build(json);
    EXPECT_EQ(asyncfem::toString(simulation.problem->settings().forceModel), type);
    for (int k = 0; k < 10; ++k) simulation.integrator->step();
    // Same direction and, at this strain (|u| / size ~1e-3 or less), within 10 % of the
    // linear model's sag: the materials agree with linear FEM to first order.
    const Eigen::VectorXd& u = simulation.integrator->displacement();
    const Eigen::VectorXd& v = linear.integrator->displacement();
    ASSERT_GT(v.cwiseAbs().maxCoeff(), 0.0);
    EXPECT_LT((u - v).cwiseAbs().maxCoeff(), 0.1 * v.cwiseAbs().maxCoeff()) << type;
  }
  json["forceModel"] = {{"type", "corotational"}, {"enforceSPD", true}};
  EXPECT_NE(sceneError(json).find("forceModel.enforceSPD: only the hyperelastic force models"), std::string::npos)
      << sceneError(json);
  json["forceModel"] = {{"type", "neo-hookean"}, {"inversionThreshold", 1.5}};
  EXPECT_NE(sceneError(json).find("forceModel.inversionThreshold: expected a principal stretch in (0, 1)"),
            std::string::npos)
      << sceneError(json);
  json["forceModel"] = {{"type", "stvk"}, {"enforceSPD", true}};
  EXPECT_NE(sceneError(json).find("forceModel.enforceSPD: the Green-strain StVK"), std::string::npos)
      << sceneError(json);
  json["forceModel"] = {{"type", "neo-hookean"}, {"mooneyRivlin", {{"mu01", 1}}}};
  EXPECT_NE(sceneError(json).find("forceModel.mooneyRivlin: only with"), std::string::npos) << sceneError(json);
  json["forceModel"] = {{"type", "neo-hookean"}};
  json["integrator"]["options"] = {{"pcgTolerance", 2.0}};
  EXPECT_NE(sceneError(json).find("integrator.options.pcgTolerance"), std::string::npos) << sceneError(json);
  json["integrator"]["options"] = {{"pcgSinglePrecision", 1}};
  EXPECT_NE(sceneError(json).find("integrator.options.pcgSinglePrecision"), std::string::npos) << sceneError(json);
}

}  // namespace

// A scene on Vega's CUBIC mesh runs linear FEM, StVK, corotational FEM and neo-Hookean (with the
// scene's inversion options) with the single-rate integrators, and the asynchronous integrator
// with a region given as an element set.
TEST(BuildSimulation, CubicVegSceneRunsLinearFemAndRefusesWhatNeedsTetrahedra) {
  nlohmann::json json = nlohmann::json::parse(R"({
    "mesh": {"file": "volumetricMesh/cubes.veg"},
    "fixed": {"boxes": [{"min": [-0.01, -0.01, -0.01], "max": [0.01, 1.01, 0.51]}]},
    "gravity": [0, 0, -9.81],
    "integrator": {"name": "trapezoidal", "timestep": 0.01},
    "frames": {"rate": 50, "count": 2}
  })");
  const std::filesystem::path data = ASYNCFEM_TEST_DATA_DIR;
  Simulation simulation = build(json, data);
  EXPECT_TRUE(simulation.problem->mesh().isHexahedral());
  for (int k = 0; k < 4; ++k) simulation.integrator->step();
  const Eigen::VectorXd& u = simulation.integrator->displacement();
  EXPECT_TRUE(u.allFinite());
  EXPECT_LT(u.minCoeff(), 0.0);  // gravity pulls the free end down
  for (const int v : simulation.problem->fixedVertices()) EXPECT_EQ(u.segment<3>(3 * v).norm(), 0.0);

  for (const char* type : {"stvk", "corotational"}) {
    nlohmann::json scene = json;
    scene["forceModel"] = {{"type", type}};
    Simulation nonlinear = build(scene, data);
    EXPECT_FALSE(nonlinear.integrator->system().forceModel->isLinear()) << type;
    nonlinear.integrator->step();
    EXPECT_TRUE(nonlinear.integrator->displacement().allFinite()) << type;
    EXPECT_LT(nonlinear.integrator->displacement().minCoeff(), 0.0) << type;
  }

  nlohmann::json neoHookean = json;
  neoHookean["forceModel"] = {{"type", "neo-hookean"}, {"inversionThreshold", 0.1}, {"enforceSPD", true}};
  Simulation hyperelastic = build(neoHookean, data);
  EXPECT_EQ(hyperelastic.problem->settings().hyperelastic.inversionThreshold, 0.1);
  EXPECT_TRUE(hyperelastic.problem->settings().hyperelastic.enforceSPD);
  EXPECT_FALSE(hyperelastic.integrator->system().forceModel->isLinear());
  hyperelastic.integrator->step();
  EXPECT_TRUE(hyperelastic.integrator->displacement().allFinite());
  EXPECT_LT(hyperelastic.integrator->displacement().minCoeff(), 0.0);
  // Async on the hexahedra, its region the element set 'right' (the cubes at x > 0.5), which
  // holds every free vertex: one async step of linear FEM is then m = 2 backward Euler steps
  // at hL / 2 (identity 3 of the design note), to 1e-9 relative (two factorizations); one
  // backward Euler step at hL differs by far more.
  nlohmann::json async = json;
  async["integrator"] = nlohmann::json::parse(
      R"({"name": "async", "timestep": 0.01, "options": {"regions": [{"name": "r", "ratio": 2, "elementSets": ["right"]}]}})");
  Simulation multirate = build(async, data);
  const std::vector<asyncfem::RegionSummary> regions = asyncfem::regionSummaries(*multirate.integrator);
  ASSERT_EQ(regions.size(), 1U);
  EXPECT_EQ(regions[0].vertices, 12);
  EXPECT_EQ(regions[0].ratio, 2);
  multirate.integrator->step();
  const auto backwardEuler = [&](double timestep, int steps) {
    nlohmann::json scene = json;
    scene["integrator"] = {{"name", "backward-euler"}, {"timestep", timestep}};
    Simulation single = build(scene, data);
    for (int k = 0; k < steps; ++k) single.integrator->step();
    return Eigen::VectorXd(single.integrator->displacement());
  };
  const Eigen::VectorXd substeps = backwardEuler(0.005, 2), oneStep = backwardEuler(0.01, 1);
  const Eigen::VectorXd& u1 = multirate.integrator->displacement();
  const double scale = substeps.lpNorm<Eigen::Infinity>();
  EXPECT_GT(scale, 0.0);
  EXPECT_LT((u1 - substeps).lpNorm<Eigen::Infinity>(), 1e-9 * scale);
  EXPECT_GT((u1 - oneStep).lpNorm<Eigen::Infinity>(), 1e-3 * scale);
}
