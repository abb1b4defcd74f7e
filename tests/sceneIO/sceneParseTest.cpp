// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <asyncfem/sceneIO/scene.hpp>
#include <cmath>

#include "sceneTestUtilities.hpp"

namespace {

using asyncfem::Scene;

TEST(SceneParse, DefaultsOfAMinimalScene) {
  const auto json = nlohmann::json::parse(R"({"mesh": {"file": "m.veg"}, "integrator": {"timestep": 0.01}})");
  const Scene scene = asyncfem::parseScene(json, "", "s.json");
  EXPECT_EQ(scene.sourceName, "s.json");
  EXPECT_EQ(scene.mesh.source, Scene::MeshSource::file);
  EXPECT_EQ(scene.mesh.file, std::filesystem::path("m.veg"));
  EXPECT_TRUE(scene.materials.empty());
  EXPECT_TRUE(scene.fixed.sets.empty());
  EXPECT_TRUE(scene.fixed.boxes.empty());
  EXPECT_FALSE(scene.fixed.bouFile.has_value());
  EXPECT_TRUE(scene.gravity.isZero(0.0));
  EXPECT_TRUE(scene.forces.empty());
  EXPECT_EQ(scene.mass, asyncfem::MassType::consistent);
  EXPECT_EQ(scene.rayleighAlpha, 0.0);
  EXPECT_EQ(scene.rayleighBeta, 0.0);
  EXPECT_EQ(scene.forceModel, Scene::ForceModelKind::linear);
  EXPECT_EQ(scene.integrator.name, "backward-euler");
  EXPECT_EQ(scene.timing.timestep, 0.01);
  // 0.01 does not divide the frame interval 1/30 s: the scene is still read, with the
  // timestep as written, and the error comes where the timing is used (requireFrameTiming).
  EXPECT_FALSE(scene.timing.resolved());
  EXPECT_TRUE(scene.integrator.options.is_object() && scene.integrator.options.empty());
  EXPECT_EQ(scene.timing.frameRate, 30.0);
  EXPECT_EQ(scene.timing.frameCount, 60);
  EXPECT_TRUE(scene.output.file.empty());
  EXPECT_TRUE(scene.output.vtuFolder.empty());
  EXPECT_EQ(scene.output.vtuEncoding, asyncfem::VtuEncoding::binary);
  EXPECT_FALSE(scene.output.velocities);
  EXPECT_FALSE(scene.output.sync);
}

TEST(SceneParse, EveryKeyIsRead) {
  const auto json = nlohmann::json::parse(R"({
    "description": "all keys",
    "mesh": {"generator": "beam", "length": 2, "height": 0.5, "depth": 0.25, "cellsAlongLength": 8,
             "tipFraction": 0.25, "body": {"density": 900, "youngsModulus": 2e6, "poissonRatio": 0.3},
             "tip": {"name": "cap", "density": 100, "youngsModulus": 3e7, "poissonRatio": 0.2}},
    "materials": [{"set": "tip", "youngsModulus": 4e7}],
    "fixed": {"sets": ["root"], "boxes": [{"min": [0, 0, 0], "max": [0.1, 1, 1]}], "bou": "sub/fixed.bou"},
    "gravity": [0, -9.81, 0],
    "forces": [{"type": "pull", "set": "tip", "force": [0, -5, 0], "window": [0, 0.5]},
               {"type": "impulse", "vertices": [3, 4], "impulse": [1, 0, 0], "time": 0.25}],
    "mass": "lumped",
    "damping": {"alpha": 0.1, "beta": 0.001},
    "forceModel": {"type": "corotational", "tangent": "exact"},
    "integrator": {"name": "trapezoidal", "timestep": 0.005, "options": {"solver": "umfpack", "anything": 1}},
    "frames": {"rate": 25, "count": 7},
    "output": {"file": "out/run.afsim", "vtu": {"folder": "out/vtu", "every": 2, "encoding": "ascii"}, "velocities": true, "sync": true}
  })");
  const Scene scene = asyncfem::parseScene(json, "scenes", "s.json");
  EXPECT_EQ(scene.description, "all keys");
  ASSERT_EQ(scene.mesh.source, Scene::MeshSource::beam);
  EXPECT_EQ(scene.mesh.beam.length, 2.0);
  EXPECT_EQ(scene.mesh.beam.height, 0.5);
  EXPECT_EQ(scene.mesh.beam.depth, 0.25);
  EXPECT_EQ(scene.mesh.beam.cellsAlongLength, 8);
  EXPECT_EQ(scene.mesh.beam.tipFraction, 0.25);
  EXPECT_EQ(scene.mesh.beam.body, (asyncfem::Material{"body", 900, 2e6, 0.3}));
  EXPECT_EQ(scene.mesh.beam.tip, (asyncfem::Material{"cap", 100, 3e7, 0.2}));
  ASSERT_EQ(scene.materials.size(), 1U);
  EXPECT_EQ(scene.materials[0].set, "tip");
  EXPECT_EQ(scene.materials[0].youngsModulus, 4e7);
  EXPECT_FALSE(scene.materials[0].density.has_value());
  EXPECT_EQ(scene.fixed.sets, std::vector<std::string>{"root"});
  ASSERT_EQ(scene.fixed.boxes.size(), 1U);
  EXPECT_EQ(scene.fixed.boxes[0].max, Eigen::Vector3d(0.1, 1, 1));
  EXPECT_EQ(scene.fixed.bouFile, std::filesystem::path("scenes/sub/fixed.bou"));
  EXPECT_EQ(scene.gravity, Eigen::Vector3d(0, -9.81, 0));
  ASSERT_EQ(scene.forces.size(), 2U);
  EXPECT_EQ(scene.forces[0].type, Scene::ForceType::pull);
  EXPECT_EQ(scene.forces[0].set, "tip");
  EXPECT_EQ(scene.forces[0].end, 0.5);
  EXPECT_EQ(scene.forces[1].type, Scene::ForceType::impulse);
  EXPECT_EQ(scene.forces[1].vertices, (std::vector<int>{3, 4}));
  EXPECT_EQ(scene.forces[1].time, 0.25);
  EXPECT_EQ(scene.mass, asyncfem::MassType::lumped);
  EXPECT_EQ(scene.rayleighAlpha, 0.1);
  EXPECT_EQ(scene.rayleighBeta, 0.001);
  EXPECT_EQ(scene.forceModel, Scene::ForceModelKind::corotational);
  EXPECT_EQ(scene.tangent, Scene::Tangent::exact);
  EXPECT_EQ(scene.integrator.name, "trapezoidal");
  // Options pass through unparsed: the integrator's factory judges them.
  EXPECT_EQ(scene.integrator.options["anything"], 1);
  EXPECT_EQ(scene.timing.frameRate, 25.0);
  EXPECT_EQ(scene.timing.frameCount, 7);
  EXPECT_EQ(scene.timing.timestep, 0.005);
  EXPECT_EQ(scene.timing.stepsPerFrame, 8);  // (1 / 25) / 0.005
  EXPECT_EQ(scene.output.file, std::filesystem::path("scenes/out/run.afsim"));
  EXPECT_EQ(scene.output.vtuFolder, std::filesystem::path("scenes/out/vtu"));
  EXPECT_EQ(scene.output.vtuEvery, 2);
  EXPECT_EQ(scene.output.vtuEncoding, asyncfem::VtuEncoding::ascii);
  EXPECT_TRUE(scene.output.velocities);
  EXPECT_TRUE(scene.output.sync);
}

TEST(SceneParse, PullWithoutWindowLastsForever) {
  auto json = asyncfem::test::smallScene();
  json["forces"] = nlohmann::json::parse(R"([{"type": "pull", "set": "xmax", "force": [1, 2, 3]}])");
  const Scene scene = asyncfem::parseScene(json, "", "s.json");
  ASSERT_EQ(scene.forces.size(), 1U);
  EXPECT_EQ(scene.forces[0].start, 0.0);
  EXPECT_TRUE(std::isinf(scene.forces[0].end));
}

TEST(SceneParse, RelativePathsResolveAgainstTheSceneFolder) {
  const asyncfem::test::ScratchFolder folder;
  const auto path = folder.write("scenes/a/scene.json", R"({
    // comments are allowed
    "mesh": {"file": "../meshes/m.veg"},
    "fixed": {"bou": "fixed.bou"},
    "integrator": {"timestep": 0.01},
    "output": {"file": "out/a.afsim", "vtu": {"folder": "/abs/vtu"}}
  })");
  const Scene scene = asyncfem::loadScene(path);
  EXPECT_EQ(scene.sourceName, path.string());
  EXPECT_EQ(scene.baseDirectory, folder.path() / "scenes/a");
  EXPECT_EQ(scene.mesh.file, folder.path() / "scenes/meshes/m.veg");
  EXPECT_EQ(*scene.fixed.bouFile, folder.path() / "scenes/a/fixed.bou");
  EXPECT_EQ(scene.output.file, folder.path() / "scenes/a/out/a.afsim");
  EXPECT_EQ(scene.output.vtuFolder, std::filesystem::path("/abs/vtu"));
}

TEST(SceneParse, ShippedBeamSceneParses) {
  const Scene scene = asyncfem::loadScene(std::filesystem::path(ASYNCFEM_MODELS_DIR) / "beam/beam.json");
  EXPECT_FALSE(scene.forces.empty());
  EXPECT_EQ(scene.fixed.sets, std::vector<std::string>{"root"});
}

}  // namespace
