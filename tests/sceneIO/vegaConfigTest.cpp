// SPDX-License-Identifier: BSD-3-Clause
// Vega FEM simulator configs read as scenes: the shipped example, each key's mapping, the
// spellings Vega accepts, and one test per refusal checking that the message names the
// file, the line and the key.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/sceneIO/vegaConfig.hpp>
#include <filesystem>
#include <string>

namespace {

namespace fs = std::filesystem;
using namespace asyncfem;

const fs::path vegaData = fs::path(ASYNCFEM_TEST_DATA_DIR) / "vega";

// The keys Vega requires, around the lines a test adds; the mesh and .bou of tests/data/vega.
std::string minimalConfig(const std::string& extra) {
  return "*volumetricMeshFilename\nbar.veg\n*timestep\n0.01\n*dampingMassCoef\n0\n*dampingStiffnessCoef\n0\n" + extra;
}

VegaConfig parse(const std::string& text) { return parseVegaConfig(text, vegaData, "test.config"); }

// The message of the Error parsing text throws (empty, and a test failure, if none).
std::string errorOf(const std::string& text) {
  try {
    parse(text);
  } catch (const Error& error) {
    return error.what();
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return "";
}

const VegaConfigKey& keyNamed(const VegaConfig& config, const std::string& key) {
  for (const VegaConfigKey& entry : config.keys) {
    if (entry.key == key) return entry;
  }
  throw std::runtime_error("no key " + key);
}

TEST(VegaConfig, TheShippedCantileverMapsEveryPhysicalKey) {
  const VegaConfig config = readVegaConfig(vegaData / "cantilever.config");
  const Scene& scene = config.scene;
  EXPECT_EQ(scene.mesh.file, (vegaData / "bar.veg").lexically_normal());
  ASSERT_TRUE(scene.fixed.bouFile.has_value());
  EXPECT_EQ(*scene.fixed.bouFile, (vegaData / "bar-root.bou").lexically_normal());
  EXPECT_EQ(scene.integrator.name, "backward-euler");  // the live value after two commented ones
  EXPECT_EQ(scene.forceModel, Scene::ForceModelKind::corotational);
  EXPECT_EQ(scene.tangent, Scene::Tangent::simple);  // warp 1
  EXPECT_EQ(scene.rayleighAlpha, 0.1);
  EXPECT_EQ(scene.rayleighBeta, 0.001);
  EXPECT_EQ(scene.gravity, Eigen::Vector3d(0.0, -9.81, 0.0));
  // One Vega frame (timestep 0.01) of two substeps: h = 0.005. The frame rate is 1 / 0.01
  // and h = (1 / rate) / 2: two roundings, so h agrees with 0.005 to a few ulps (1e-15).
  EXPECT_EQ(scene.timing.stepsPerFrame, 2);
  EXPECT_NEAR(scene.timing.timestep, 0.005, 1e-15);
  EXPECT_NEAR(scene.timing.frameInterval, 0.01, 1e-15);
  ASSERT_TRUE(config.secondaryRenderingMesh.has_value());
  EXPECT_EQ(*config.secondaryRenderingMesh, (vegaData / "bar-box.obj").lexically_normal());
  EXPECT_EQ(*config.secondaryInterpolation, (vegaData / "bar-box.interp").lexically_normal());
  EXPECT_FALSE(config.renderingMesh.has_value());  // __none
  EXPECT_NE(keyNamed(config, "cameraRadius").outcome.find("ignored: interactive only"), std::string::npos);
  EXPECT_EQ(keyNamed(config, "cameraRadius").value, "2.5");  // tab and trailing blanks trimmed
  EXPECT_EQ(keyNamed(config, "substepsPerTimeStep").line, 24u);
  for (const VegaConfigKey& key : config.keys) EXPECT_FALSE(key.outcome.empty()) << key.key;
}

TEST(VegaConfig, LoadSceneDispatchesOnTheExtension) {
  const Scene viaLoadScene = loadScene(vegaData / "cantilever.config");
  const VegaConfig config = readVegaConfig(vegaData / "cantilever.config");
  EXPECT_EQ(viaLoadScene.integrator.name, config.scene.integrator.name);
  EXPECT_EQ(viaLoadScene.timing, config.scene.timing);
  EXPECT_EQ(viaLoadScene.sourceName, (vegaData / "cantilever.config").string());
  // The equivalent scene JSON is itself a scene.
  const Scene reparsed = parseScene(config.sceneJson, vegaData, "equivalent.json");
  EXPECT_EQ(reparsed.mesh.file, config.scene.mesh.file);
  EXPECT_EQ(reparsed.timing, config.scene.timing);
  EXPECT_EQ(sceneFileJson(vegaData / "cantilever.config"), config.sceneJson);
}

TEST(VegaConfig, BooleansInEitherSpellingAndCommentedAlternatives) {
  for (const char* on : {"1", "true", "TRUE", "True"}) {
    const VegaConfig config = parse(minimalConfig(std::string("*addGravity\n") + on + "\n*g\n10\n"));
    EXPECT_EQ(config.scene.gravity, Eigen::Vector3d(0.0, -10.0, 0.0)) << on;
  }
  for (const char* off : {"0", "false", "False"}) {
    const VegaConfig config = parse(minimalConfig(std::string("*addGravity\n") + off + "\n*g\n10\n"));
    EXPECT_EQ(config.scene.gravity, Eigen::Vector3d::Zero()) << off;
  }
  const VegaConfig config = parse(
      "# header\n\n   *volumetricMeshFilename  \r\n\n#   other.veg\n  bar.veg  \r\n*timestep\n# 0.1\n\n1E-2\n"
      "*dampingMassCoef\n0\n*dampingStiffnessCoef\n0\n");
  EXPECT_EQ(config.scene.mesh.file, (vegaData / "bar.veg").lexically_normal());
  EXPECT_NEAR(config.scene.timing.timestep, 0.01, 1e-15);
  EXPECT_EQ(config.scene.integrator.name, "trapezoidal");           // Vega's default solver
  EXPECT_EQ(config.scene.forceModel, Scene::ForceModelKind::stvk);  // Vega's default model
  EXPECT_FALSE(config.scene.fixed.bouFile.has_value());
}

TEST(VegaConfig, SolversMapToTheIntegratorsOfTheSameMethod) {
  const std::pair<const char*, const char*> solvers[] = {{"implicitNewmark", "trapezoidal"},
                                                         {"implicitBackwardEuler", "backward-euler"},
                                                         {"centralDifferences", "central-differences"},
                                                         {"symplecticEuler", "symplectic-euler"}};
  for (const auto& [vega, toolkit] : solvers) {
    EXPECT_EQ(parse(minimalConfig(std::string("*solver\n") + vega + "\n")).scene.integrator.name, toolkit);
  }
  // The obsolete key still selects the solver; *solver wins when both are given.
  EXPECT_EQ(parse(minimalConfig("*implicitSolverMethod\nimplicitBackwardEuler\n")).scene.integrator.name,
            "backward-euler");
  EXPECT_EQ(parse(minimalConfig("*implicitSolverMethod\nimplicitBackwardEuler\n*solver\nsymplecticEuler\n"))
                .scene.integrator.name,
            "symplectic-euler");
  const VegaConfig newton = parse(minimalConfig("*solver\nimplicitBackwardEuler\n*maxIterations\n5\n*epsilon\n1e-7\n"));
  EXPECT_EQ(newton.scene.integrator.options.at("maxIterations"), 5);
  EXPECT_EQ(newton.scene.integrator.options.at("tolerance"), 1e-7);
  EXPECT_EQ(newton.scene.integrator.options.at("rayleighStiffnessAtIterate"), true);
  // Explicit solvers take no Newton options (their factories would reject them).
  EXPECT_TRUE(
      parse(minimalConfig("*solver\ncentralDifferences\n*maxIterations\n3\n")).scene.integrator.options.empty());
  // The trapezoidal rule is Newmark at beta 1/4, gamma 1/2: those values are accepted.
  EXPECT_NO_THROW(parse(minimalConfig("*newmarkBeta\n0.25\n*newmarkGamma\n0.5\n")));
}

TEST(VegaConfig, DeformableModelsMapToForceModels) {
  EXPECT_EQ(parse(minimalConfig("*deformableObjectMethod\nLinearFEM\n")).scene.forceModel,
            Scene::ForceModelKind::linear);
  EXPECT_EQ(parse(minimalConfig("*deformableObjectMethod\nCLFEM\n*corotationalLinearFEM_warp\n0\n")).scene.forceModel,
            Scene::ForceModelKind::linear);
  const Scene exact = parse(minimalConfig("*deformableObjectMethod\nCLFEM\n*corotationalLinearFEM_warp\n2\n")).scene;
  EXPECT_EQ(exact.forceModel, Scene::ForceModelKind::corotational);
  EXPECT_EQ(exact.tangent, Scene::Tangent::exact);
  const Scene neoHookean = parse(minimalConfig("*deformableObjectMethod\nInvertibleFEM\n*invertibleMaterial\n"
                                               "neoHookean\n*inversionThreshold\n0.1\n*enableCompressionResistance\n"
                                               "true\n*compressionResistance\n200\n"))
                               .scene;
  EXPECT_EQ(neoHookean.forceModel, Scene::ForceModelKind::neoHookean);
  EXPECT_EQ(neoHookean.hyperelastic.inversionThreshold, 0.1);
  EXPECT_EQ(neoHookean.hyperelastic.inversionHandling, InversionHandling::vegaClamp);
  EXPECT_TRUE(neoHookean.hyperelastic.enableCompressionResistance);
  EXPECT_EQ(neoHookean.hyperelastic.compressionResistance, 200.0);
  const Scene invertibleStVK = parse(minimalConfig("*deformableObjectMethod\nInvertibleFEM\n")).scene;
  EXPECT_EQ(invertibleStVK.forceModel, Scene::ForceModelKind::stvk);
  EXPECT_EQ(invertibleStVK.hyperelastic.stvkFormulation, StVKFormulation::principalStretches);
  EXPECT_EQ(parse(minimalConfig("*deformableObjectMethod\nInvertibleFEM\n*invertibleMaterial\nMooneyRivlin\n"))
                .scene.forceModel,
            Scene::ForceModelKind::mooneyRivlin);
  // Plain StVK is Vega's Green-strain StVK.
  EXPECT_EQ(parse(minimalConfig("*deformableObjectMethod\nStVK\n")).scene.hyperelastic.stvkFormulation,
            StVKFormulation::greenStrain);
}

// Vega's config for the agreement scenario corotational-simple-bar (tests/data/vega/README.md:
// CLFEM warp 1, backward Euler at h = 0.01 s, Rayleigh 0.5 / 0.01, gravity, the root fixed)
// runs the trajectory of that scenario's scene, which VegaAgreement checks against Vega's
// own run to 3e-11. The scene there asks for exact solves (reuseFactor false); the config
// gets the default path, documented to stay within 1e-8 of it relative to max |u|
// (docs/scene-format.md, integrator options), so 1e-8 is the tolerance here (measured: 0,
// as with one Newton iteration per step both paths factor at every step).
TEST(VegaConfig, RunsTheTrajectoryOfTheVegaAgreementScene) {
  const Scene fromConfig = parse(
                               "*volumetricMeshFilename\nbar.veg\n*fixedVerticesFilename\nbar-root.bou\n*solver\n"
                               "implicitBackwardEuler\n*deformableObjectMethod\nCLFEM\n*corotationalLinearFEM_warp\n1\n"
                               "*timestep\n0.01\n*dampingMassCoef\n0.5\n*dampingStiffnessCoef\n0.01\n*addGravity\n1\n")
                               .scene;
  const Scene agreement = loadScene(vegaData / "corotational-simple-bar.json");
  Simulation config = buildSimulation(fromConfig);
  Simulation reference = buildSimulation(agreement);
  ASSERT_EQ(config.problem->fixedVertices(), reference.problem->fixedVertices());  // the .bou is the root set
  double largest = 0.0;
  for (int frame = 0; frame < 30; ++frame) {
    advanceFrame(config, frame);
    advanceFrame(reference, frame);
    const Eigen::VectorXd& expected = reference.integrator->displacement();
    largest = std::max(largest, (config.integrator->displacement() - expected).lpNorm<Eigen::Infinity>() /
                                    expected.lpNorm<Eigen::Infinity>());
  }
  EXPECT_LE(largest, 1e-8);
  EXPECT_GT(reference.integrator->displacement().lpNorm<Eigen::Infinity>(), 1e-3);  // the bar did bend
}

// Each refusal: the message names the file, the line and the key.
struct Refusal {
  const char* name;
  std::string text;
  std::string expected;  // a part of the message, starting with "test.config:LINE: *key"
};

class VegaConfigRefusal : public ::testing::TestWithParam<Refusal> {};

TEST_P(VegaConfigRefusal, NamesFileLineAndKey) {
  const std::string message = errorOf(GetParam().text);
  EXPECT_NE(message.find(GetParam().expected), std::string::npos) << message;
}

INSTANTIATE_TEST_SUITE_P(
    Errors, VegaConfigRefusal,
    ::testing::Values(
        Refusal{"UnknownKey", minimalConfig("*timeStepSize\n0.1\n"), "test.config:9: *timeStepSize: unknown option"},
        Refusal{"MisspeltInterpolationKey", minimalConfig("*renderingMeshInterpolationFilename\nx.interp\n"),
                "test.config:9: *renderingMeshInterpolationFilename: unknown option (did you mean "
                "*secondaryRenderingMeshInterpolationFilename?)"},
        Refusal{"UnknownDeformableModel", minimalConfig("*deformableObjectMethod\nHyperFEM\n"),
                "test.config:9: *deformableObjectMethod: unknown deformable model \"HyperFEM\""},
        Refusal{"MassSpring", minimalConfig("*deformableObjectMethod\nMassSpring\n"),
                "test.config:9: *deformableObjectMethod: mass-spring systems are not supported"},
        Refusal{
            "MissingMeshFile",
            "*volumetricMeshFilename\nmissing.veg\n*timestep\n0.01\n*dampingMassCoef\n0\n*dampingStiffnessCoef\n0\n",
            "test.config:1: *volumetricMeshFilename: no such file: " + (vegaData / "missing.veg").string()},
        Refusal{"MissingRequiredKey", "*volumetricMeshFilename\nbar.veg\n*dampingMassCoef\n0\n",
                "test.config: required option *timestep is missing"},
        Refusal{"ValueMissing", minimalConfig("*g\n*addGravity\n1\n"), "test.config:9: *g: no value before"},
        Refusal{"GivenTwice", minimalConfig("*timestep\n0.02\n"),
                "test.config:9: *timestep: given twice (first on line 3)"},
        Refusal{"NotABoolean", minimalConfig("*addGravity\nyes\n"), "test.config:9: *addGravity: expected a boolean"},
        Refusal{"NotANumber", minimalConfig("*g\n9.81m\n"), "test.config:9: *g: expected a finite number"},
        Refusal{"ValueWithoutKey", "bar.veg\n", "test.config:1: \"bar.veg\" is not an option"},
        Refusal{"ForwardEuler", minimalConfig("*solver\nEuler\n"), "test.config:9: *solver: explicit (forward) Euler"},
        Refusal{"UnknownSolver", minimalConfig("\n*solver\nimplicitEuler\n"),
                "test.config:10: *solver: unknown solver \"implicitEuler\""},
        Refusal{"NewmarkBeta", minimalConfig("*newmarkBeta\n0.3\n"), "test.config:9: *newmarkBeta: the toolkit's"},
        Refusal{"FrequencyScaling", minimalConfig("*frequencyScaling\n2\n"),
                "test.config:9: *frequencyScaling: scales the internal forces"},
        Refusal{"LaplacianDamping", minimalConfig("*dampingLaplacianCoef\n0.1\n"),
                "test.config:9: *dampingLaplacianCoef: Laplacian damping is not supported"},
        Refusal{"ForceLoads", minimalConfig("*forceLoadsFilename\nbar.veg\n"),
                "test.config:9: *forceLoadsFilename: force load files are not supported"},
        Refusal{"InitialVelocity", minimalConfig("*initialVelocityFilename\nbar.veg\n"),
                "test.config:9: *initialVelocityFilename: an initial state is not supported"},
        Refusal{"Plasticity", minimalConfig("*plasticThreshold\n0.5\n"), "test.config:9: *plasticThreshold: plastic"},
        Refusal{"WarpOutOfRange", minimalConfig("*deformableObjectMethod\nCLFEM\n*corotationalLinearFEM_warp\n3\n"),
                "test.config:11: *corotationalLinearFEM_warp: expected 0, 1 or 2"},
        Refusal{"InversionThreshold", minimalConfig("*deformableObjectMethod\nInvertibleFEM\n*inversionThreshold\n2\n"),
                "test.config:11: *inversionThreshold: expected a principal stretch in (0, 1)"},
        Refusal{"RenderMeshWithoutWeights", minimalConfig("*secondaryRenderingMeshFilename\nbar-box.obj\n"),
                "test.config:9: *secondaryRenderingMeshFilename: needs *secondaryRenderingMeshInterpolationFilename"},
        Refusal{"NegativeDamping",
                "*volumetricMeshFilename\nbar.veg\n*timestep\n0.01\n*dampingMassCoef\n-1\n"
                "*dampingStiffnessCoef\n0\n",
                "test.config:5: *dampingMassCoef: expected a number >= 0"}),
    [](const ::testing::TestParamInfo<Refusal>& info) { return info.param.name; });

TEST(VegaConfig, RefusalsAreParseErrorsCarryingTheLine) {
  try {
    parse(minimalConfig("*timeStepSize\n0.1\n"));
    FAIL() << "no error";
  } catch (const ParseError& error) {
    EXPECT_EQ(error.file(), "test.config");
    EXPECT_EQ(error.line(), 9u);
  }
}

}  // namespace
