// SPDX-License-Identifier: BSD-3-Clause
// One case per documented scene error (docs/scene-format.md, "Errors"): each must name
// the scene and the full key path of what is wrong.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <string>

#include "sceneTestUtilities.hpp"

namespace {

struct ErrorCase {
  std::string name;
  std::string patch;     ///< JSON merge patch (RFC 7396) applied to smallScene(); null removes a key
  std::string expected;  ///< must occur in the message
  bool atBuild = false;  ///< found by buildSimulation rather than parseScene
};

std::ostream& operator<<(std::ostream& out, const ErrorCase& c) { return out << c.name; }

std::string errorOf(const ErrorCase& c) {
  nlohmann::json json = asyncfem::test::smallScene();
  json.merge_patch(nlohmann::json::parse(c.patch));
  try {
    const asyncfem::Scene scene = asyncfem::parseScene(json, "", "scene.json");
    if (c.atBuild) {
      (void)asyncfem::buildSimulation(scene);
    }
  } catch (const asyncfem::Error& error) {
    return error.what();
  }
  return "(no error)";
}

class SceneErrors : public ::testing::TestWithParam<ErrorCase> {};

TEST_P(SceneErrors, NamesTheKey) {
  const ErrorCase& c = GetParam();
  const std::string message = errorOf(c);
  EXPECT_NE(message.find(c.expected), std::string::npos) << "message: " << message;
  EXPECT_EQ(message.rfind("scene.json: ", 0), 0U) << "message: " << message;
}

const ErrorCase cases[] = {
    {"UnknownTopLevelKey", R"({"colour": "red"})", "scene.json: colour: unknown key"},
    {"MisspelledNestedKey", R"({"integrator": {"timestpe": 1}})", "scene.json: integrator.timestpe: unknown key"},
    {"TopLevelNotObject", R"({"mesh": 3})", "scene.json: mesh: expected an object"},
    {"MeshMissing", R"({"mesh": null})", "scene.json: mesh: required key missing"},
    {"MeshFileAndGenerator", R"({"mesh": {"file": "a.veg"}})",
     "scene.json: mesh: give either \"file\" or \"generator\""},
    {"MeshGeneratorUnknown", R"({"mesh": {"generator": "sphere"}})",
     "scene.json: mesh.generator: unknown value \"sphere\""},
    {"MeshBoxSizeNotPositive", R"({"mesh": {"size": [1, 0, 1]}})", "scene.json: mesh.size: expected three sizes > 0"},
    {"MeshBoxCellsNotInteger", R"({"mesh": {"cells": [2, 1.5, 1]}})", "scene.json: mesh.cells[1]: expected an integer"},
    {"MeshBoxUnknownKey", R"({"mesh": {"length": 2}})", "scene.json: mesh.length: unknown key"},
    {"MeshMaterialPoisson", R"({"mesh": {"material": {"poissonRatio": 0.5}}})",
     "scene.json: mesh.material.poissonRatio: expected a Poisson ratio in (-1, 0.5)"},
    {"MeshMaterialDensity", R"({"mesh": {"material": {"density": -1}}})",
     "scene.json: mesh.material.density: expected a density > 0"},
    {"MeshBeamLength",
     R"({"mesh": {"generator": "beam", "size": null, "cells": null, "material": null, "length": -1}})",
     "scene.json: mesh.length: expected a number > 0"},
    {"MeshBeamTipFraction",
     R"({"mesh": {"generator": "beam", "size": null, "cells": null, "material": null, "tipFraction": 1}})",
     "scene.json: mesh.tipFraction: expected a fraction in [0, 1)"},
    {"MeshBeamCells",
     R"({"mesh": {"generator": "beam", "size": null, "cells": null, "material": null, "cellsAlongLength": 0}})",
     "scene.json: mesh.cellsAlongLength: expected an integer in [1, 100000]"},
    {"MeshRegionMinMax",
     R"({"mesh": {"regions": [{"name": "r", "min": [1, 0, 0], "max": [0, 1, 1], "material": {}}]}})",
     "scene.json: mesh.regions[0]: expected min <= max"},
    {"MaterialsNotArray", R"({"materials": {"set": "x"}})", "scene.json: materials: expected an array"},
    {"MaterialsSetMissing", R"({"materials": [{"density": 3}]})", "scene.json: materials[0].set: required key missing"},
    {"MaterialsNothingToOverride", R"({"materials": [{"set": "allElements"}]})",
     "scene.json: materials[0]: gives no constant to override"},
    {"MaterialsYoungsModulus", R"({"materials": [{"set": "allElements", "youngsModulus": 0}]})",
     "scene.json: materials[0].youngsModulus: expected a Young's modulus > 0"},
    {"MaterialsUnknownSet", R"({"materials": [{"set": "nowhere", "density": 5}]})",
     "scene.json: materials[0].set: unknown element set \"nowhere\"", true},
    {"FixedSetsNotArray", R"({"fixed": {"sets": "xmin"}})", "scene.json: fixed.sets: expected an array"},
    {"FixedSetsNotString", R"({"fixed": {"sets": ["xmin", 3]}})", "scene.json: fixed.sets[1]: expected a string"},
    {"FixedUnknownSet", R"({"fixed": {"sets": ["xmin", "nowhere"]}})",
     "scene.json: fixed.sets[1]: unknown set \"nowhere\" (vertex sets: ", true},
    {"FixedBoxMinMax", R"({"fixed": {"boxes": [{"min": [0, 0, 0], "max": [1, -1, 1]}]}})",
     "scene.json: fixed.boxes[0]: expected min <= max"},
    {"FixedBoxVector", R"({"fixed": {"boxes": [{"min": [0, 0], "max": [1, 1, 1]}]}})",
     "scene.json: fixed.boxes[0].min: expected [x, y, z]"},
    {"FixedBoxEmpty", R"({"fixed": {"boxes": [{"min": [5, 5, 5], "max": [6, 6, 6]}]}})",
     "scene.json: fixed.boxes[0]: selects no vertex", true},
    {"FixedBouEmptyPath", R"({"fixed": {"bou": ""}})", "scene.json: fixed.bou: expected a non-empty path"},
    {"FixedBouMissingFile", R"({"fixed": {"bou": "/nonexistent/fixed.bou"}})", "scene.json: fixed.bou: ", true},
    {"FixedEverything", R"({"fixed": {"boxes": [{"min": [-1, -1, -1], "max": [3, 3, 3]}]}})",
     "scene.json: fixed: every vertex is fixed", true},
    {"GravityNotVector", R"({"gravity": -9.81})", "scene.json: gravity: expected [x, y, z]"},
    {"ForcesNotArray", R"({"forces": {}})", "scene.json: forces: expected an array"},
    {"ForceTypeUnknown", R"({"forces": [{"type": "push", "set": "xmax"}]})",
     "scene.json: forces[0].type: unknown value \"push\""},
    {"ForceSetAndVertices", R"({"forces": [{"type": "pull", "set": "xmax", "vertices": [1], "force": [0, 0, 1]}]})",
     "scene.json: forces[0]: give either \"set\" or \"vertices\""},
    {"ForceNoTarget", R"({"forces": [{"type": "pull", "force": [0, 0, 1]}]})",
     "scene.json: forces[0]: give either \"set\" or \"vertices\""},
    {"ForceVerticesNegative", R"({"forces": [{"type": "pull", "vertices": [1, -2], "force": [0, 0, 1]}]})",
     "scene.json: forces[0].vertices[1]: expected an integer"},
    {"ForceVerticesEmpty", R"({"forces": [{"type": "pull", "vertices": [], "force": [0, 0, 1]}]})",
     "scene.json: forces[0].vertices: expected a non-empty array"},
    {"ForcePullMissingForce", R"({"forces": [{"type": "pull", "set": "xmax"}]})",
     "scene.json: forces[0].force: required key missing"},
    {"ForceWindowReversed",
     R"({"forces": [{"type": "pull", "set": "xmax", "force": [0, 0, 1]},
                    {"type": "pull", "set": "xmax", "force": [0, 0, 1], "window": [0.5, 0.1]}]})",
     "scene.json: forces[1].window: expected [start, end] with start <= end"},
    {"ForceWindowShape", R"({"forces": [{"type": "pull", "set": "xmax", "force": [0, 0, 1], "window": [0.5]}]})",
     "scene.json: forces[0].window: expected [start, end] with start <= end"},
    {"ForceImpulseKeyOnPull", R"({"forces": [{"type": "pull", "set": "xmax", "force": [0, 0, 1], "time": 1}]})",
     "scene.json: forces[0].time: unknown key"},
    {"ForceImpulseMissing", R"({"forces": [{"type": "impulse", "set": "xmax"}]})",
     "scene.json: forces[0].impulse: required key missing"},
    {"ForceImpulseTime", R"({"forces": [{"type": "impulse", "set": "xmax", "impulse": [0, 0, 1], "time": -1}]})",
     "scene.json: forces[0].time: expected a time >= 0"},
    {"ForceUnknownSet", R"({"forces": [{"type": "pull", "set": "nowhere", "force": [0, 0, 1]}]})",
     "scene.json: forces[0].set: unknown set \"nowhere\" (vertex sets: ", true},
    {"ForceVertexOutOfRange", R"({"forces": [{"type": "pull", "vertices": [0, 12], "force": [0, 0, 1]}]})",
     "scene.json: forces[0].vertices[1]: vertex 12 out of range [0, 12)", true},
    {"MassUnknown", R"({"mass": "diagonal"})", "scene.json: mass: unknown value \"diagonal\""},
    {"DampingNegative", R"({"damping": {"alpha": -0.1}})", "scene.json: damping.alpha: expected alpha >= 0"},
    {"DampingNotNumber", R"({"damping": {"beta": "0.1"}})",
     "scene.json: damping.beta: expected a number, got a string"},
    {"ForceModelUnknown", R"({"forceModel": {"type": "neo-hooke"}})",
     "scene.json: forceModel.type: unknown value \"neo-hooke\""},
    {"ForceModelTangentOnLinear", R"({"forceModel": {"type": "linear", "tangent": "exact"}})",
     "scene.json: forceModel.tangent: only the corotational force model has a tangent choice"},
    {"ForceModelTangentUnknown", R"({"forceModel": {"type": "corotational", "tangent": "approximate"}})",
     "scene.json: forceModel.tangent: unknown value \"approximate\""},
    {"IntegratorMissing", R"({"integrator": null})", "scene.json: integrator: required key missing"},
    {"TimestepMissing", R"({"integrator": {"timestep": null}})",
     "scene.json: integrator: give either \"timestep\" or \"stepsPerFrame\" (steps per frame of 1 / frames.rate)"},
    {"TimestepNotPositive", R"({"integrator": {"timestep": 0}})",
     "scene.json: integrator.timestep: expected a number > 0"},
    {"IntegratorOptionsNotObject", R"({"integrator": {"options": [1]}})",
     "scene.json: integrator.options: expected an object"},
    {"IntegratorUnknown", R"({"integrator": {"name": "runge-kutta"}})",
     "scene.json: integrator.name: unknown integrator \"runge-kutta\"", true},
    {"IntegratorOptionUnknown", R"({"integrator": {"options": {"regions": []}}})",
     "scene.json: integrator.options.regions: unknown key", true},
    {"IntegratorOptionSolver", R"({"integrator": {"options": {"solver": "mumps"}}})",
     "scene.json: integrator.options.solver: ", true},
    {"IntegratorOptionIterations", R"({"integrator": {"options": {"maxIterations": 0}}})",
     "scene.json: integrator.options.maxIterations: expected an integer in [1, 1000]", true},
    {"IntegratorOptionTolerance", R"({"integrator": {"options": {"tolerance": -1}}})",
     "scene.json: integrator.options.tolerance: expected a number > 0", true},
    {"IntegratorOptionForce", R"({"integrator": {"options": {"force": 1}}})",
     "scene.json: integrator.options.force: expected true or false", true},
    {"ExplicitAboveStableTimestep",
     R"({"mesh": {"material": {"youngsModulus": 1e8}}, "integrator": {"name": "central-differences"}})",
     "scene.json: integrator.timestep: ", true},
    {"StepsPerFrameNotInteger", R"({"integrator": {"timestep": 0.03}})",
     "scene.json: integrator.timestep: 0.03 does not divide the frame interval 1/10 s (frames.rate 10) into whole "
     "steps: 3.33333333333 steps per frame; the nearest valid timesteps are 1/30 s = 0.0333333333 s (3 steps per "
     "frame) and 1/40 s = 0.025 s (4 steps per frame); or give the steps per frame instead "
     "(integrator.stepsPerFrame)",
     true},
    {"StepLongerThanFrame", R"({"integrator": {"timestep": 0.2}})",
     "scene.json: integrator.timestep: 0.2 does not divide the frame interval 1/10 s (frames.rate 10) into whole "
     "steps: 0.5 steps per frame; the timestep is longer than a frame; the longest valid timestep is 1/10 s = 0.1 s "
     "(1 step per frame)",
     true},
    {"TimestepAndStepsPerFrame", R"({"integrator": {"stepsPerFrame": 4}})",
     "scene.json: integrator: give either \"timestep\" or \"stepsPerFrame\""},
    {"TimestepMisspelt", R"({"integrator": {"timestep": null, "timestpe": 0.01}})",
     "scene.json: integrator.timestpe: unknown key (known here: name, timestep, stepsPerFrame, options)"},
    {"StepsPerFrameNotPositive", R"({"integrator": {"timestep": null, "stepsPerFrame": 0}})",
     "scene.json: integrator.stepsPerFrame: expected an integer in [1, "},
    {"FramesRate", R"({"frames": {"rate": 0}})", "scene.json: frames.rate: expected a number > 0"},
    {"FramesCount", R"({"frames": {"count": 0}})", "scene.json: frames.count: expected an integer in [1, "},
    {"OutputFileEmpty", R"({"output": {"file": ""}})", "scene.json: output.file: expected a non-empty path"},
    {"OutputVtuFolderMissing", R"({"output": {"vtu": {"every": 2}}})",
     "scene.json: output.vtu.folder: expected a non-empty path"},
    {"OutputVtuEvery", R"({"output": {"vtu": {"folder": "v", "every": 0}}})",
     "scene.json: output.vtu.every: expected an integer in [1, "},
    {"OutputVtuEncoding", R"({"output": {"vtu": {"folder": "v", "encoding": "base64"}}})",
     "scene.json: output.vtu.encoding: unknown value \"base64\" (expected one of \"binary\", \"ascii\")"},
    {"OutputVelocitiesNotBool", R"({"output": {"velocities": "yes"}})",
     "scene.json: output.velocities: expected true or false"},
    {"OutputRegionsNotBool", R"({"output": {"regions": "yes"}})", "scene.json: output.regions: expected true or false"},
    {"OutputRegionsMisspelt", R"({"output": {"region": true}})",
     "scene.json: output.region: unknown key (known here: file, vtu, velocities, contactForces, sync, regions)"},
    {"OutputRegionsSingleRate", R"({"output": {"regions": true}})",
     "scene.json: output.regions: records the fast regions of a multirate integrator, but \"backward-euler\" is "
     "single-rate (use \"async\" with regions, or leave output.regions out)",
     true},
    {"MeshFileMissing",
     R"({"mesh": {"generator": null, "size": null, "cells": null, "material": null, "file": "/nonexistent/m.veg"}})",
     "scene.json: mesh.file: ", true},
};

INSTANTIATE_TEST_SUITE_P(Scene, SceneErrors, ::testing::ValuesIn(cases),
                         [](const ::testing::TestParamInfo<ErrorCase>& info) { return info.param.name; });

TEST(SceneErrorsFile, InvalidJsonNamesFileAndLine) {
  const asyncfem::test::ScratchFolder folder;
  const auto path = folder.write("broken.json", "{\n  \"mesh\": {\"file\": \"a.veg\"},\n  \"frames\": {rate: 3}\n}\n");
  try {
    (void)asyncfem::loadScene(path);
    FAIL() << "expected a parse error";
  } catch (const asyncfem::ParseError& error) {
    EXPECT_EQ(error.line(), 3U) << error.what();
    EXPECT_NE(std::string(error.what()).find("broken.json:3: invalid JSON"), std::string::npos) << error.what();
  }
}

// A folder or a mesh given where a scene belongs is named as such, not as invalid JSON.
TEST(SceneErrorsFile, FolderOrMeshInsteadOfASceneIsNamed) {
  const asyncfem::test::ScratchFolder folder;
  const auto mesh = folder.write("beam.veg", "*VERTICES\n");
  const auto surface = folder.write("bunny.stl", "solid bunny\n");
  for (const auto& [path, expected] :
       {std::pair{folder.path(), folder.path().string() + ": is a directory, not a scene file"},
        std::pair{mesh, mesh.string() + ": is a mesh file, not a scene (scenes are JSON; see docs/scene-format.md); "
                                        "to look at a mesh use meshInfo"},
        std::pair{surface, surface.string() +
                               ": is a surface mesh, not a scene (scenes are JSON; see "
                               "docs/scene-format.md); make a tetrahedral mesh of it with tetMesher "
                               "(tetMesher " +
                               surface.string() + " --output bunny.veg; docs/tet-mesher.md)"}}) {
    try {
      (void)asyncfem::loadScene(path);
      FAIL() << "expected an error for " << path;
    } catch (const asyncfem::Error& error) {
      EXPECT_NE(std::string(error.what()).find(expected), std::string::npos) << error.what();
    }
  }
}

TEST(SceneErrorsFile, MissingSceneFileIsNamed) {
  try {
    (void)asyncfem::loadScene("/nonexistent/scene.json");
    FAIL() << "expected an error";
  } catch (const asyncfem::Error& error) {
    EXPECT_NE(std::string(error.what()).find("/nonexistent/scene.json"), std::string::npos);
  }
}

}  // namespace
